# Sourced by the scripts that run on the lent 16-core machine (wide_node_device.sh,
# study_device.sh), from the repository root with .devbundle carried (bench/device_bundle.sh):
# prints the processor, picks the build the processor supports (x86-64-v4 where it has
# AVX-512, else v3) and writes /tmp/NAME for each NAME given, a wrapper that runs
# .devbundle/NAME-LEVEL through the bundle's own loader and libraries.
#   source bench/device_env.sh bench_scaling shockmpm
B="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/.devbundle"
grep -m1 "model name" /proc/cpuinfo; nproc; free -g | head -2
level=v3; grep -qw avx512f /proc/cpuinfo && grep -qw avx512bw /proc/cpuinfo && level=v4
echo "build: x86-64-$level"
LOADER=$(ls "$B"/lib/ld-linux-x86-64.so.* | head -1)
for name in "$@"; do
  cat > "/tmp/$name" <<EOS
#!/bin/sh
exec "$LOADER" --library-path "$B/lib" "$B/$name-$level" "\$@"
EOS
  chmod +x "/tmp/$name"
done
