#include "engine/checkpoint.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace smpm {

namespace {

constexpr char kMagic[8] = {'S', 'M', 'P', 'M', 'C', 'K', 'P', '1'};
enum : std::uint8_t { kDouble = 1, kU32 = 2, kU8 = 3, kI64 = 4, kText = 5 };
const char* const kTypeName[] = {"?", "double array", "uint32 array", "uint8 array", "integer", "text"};

std::size_t type_size(std::uint8_t t) {
  switch (t) {
    case kDouble: case kI64: return 8;
    case kU32: return 4;
    case kU8: case kText: return 1;
    default: return 0;
  }
}

std::string errno_text() { return std::strerror(errno); }

// fsync of a file or directory by name (the rename of a checkpoint is durable once its
// directory is synced); failures here are not fatal: the data itself was synced
void fsync_path(const std::filesystem::path& p) {
  const int fd = ::open(p.c_str(), O_RDONLY);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

void StreamHash::update(const void* data, std::size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  if (fill_ > 0) {  // complete a partial word first
    const std::size_t k = std::min(n, 8 - fill_);
    std::memcpy(buf_ + fill_, p, k);
    fill_ += k;
    p += k;
    n -= k;
    if (fill_ < 8) return;
    std::uint64_t w;
    std::memcpy(&w, buf_, 8);
    mix(w);
    fill_ = 0;
  }
  for (; n >= 8; n -= 8, p += 8) {
    std::uint64_t w;
    std::memcpy(&w, p, 8);
    mix(w);
  }
  std::memcpy(buf_, p, n);  // n < 8, fill_ == 0
  fill_ = n;
}

std::uint64_t StreamHash::value() const {
  StreamHash t = *this;
  if (t.fill_ > 0) {
    unsigned char b[8] = {};
    std::memcpy(b, t.buf_, t.fill_);
    std::uint64_t w;
    std::memcpy(&w, b, 8);
    t.mix(w);
    t.mix(t.fill_);
  }
  return t.h_;
}

// ---------------------------------------------------------------------------------------------
CheckpointWriter::CheckpointWriter(std::filesystem::path file) : file_(std::move(file)) {
  tmp_ = file_;
  tmp_ += ".tmp";
  std::error_code ec;
  std::filesystem::create_directories(file_.parent_path(), ec);
  f_ = std::fopen(tmp_.c_str(), "wb");
  if (!f_) fail("cannot create");
  write(kMagic, sizeof kMagic);
}

CheckpointWriter::~CheckpointWriter() {
  if (f_) std::fclose(f_);
  if (!committed_) {
    std::error_code ec;
    std::filesystem::remove(tmp_, ec);
  }
}

void CheckpointWriter::fail(const std::string& what) {
  const std::string why = errno_text();
  if (f_) std::fclose(f_);
  f_ = nullptr;
  std::error_code ec;
  std::filesystem::remove(tmp_, ec);
  throw CheckpointError(what + " checkpoint " + tmp_.string() + ": " + why);
}

void CheckpointWriter::write(const void* data, std::size_t bytes) {
  if (bytes > 0 && std::fwrite(data, 1, bytes, f_) != bytes) fail("cannot write");
  hash_.update(data, bytes);
}

void CheckpointWriter::record(const std::string& name, std::uint8_t type, std::uint64_t count, const void* data,
                              std::size_t bytes) {
  const auto len = static_cast<std::uint32_t>(name.size());
  write(&len, sizeof len);
  write(name.data(), name.size());
  write(&type, 1);
  write(&count, sizeof count);
  write(data, bytes);
}

void CheckpointWriter::put(const std::string& name, const std::vector<double>& v) {
  record(name, kDouble, v.size(), v.data(), v.size() * sizeof(double));
}
void CheckpointWriter::put(const std::string& name, const std::vector<std::uint32_t>& v) {
  record(name, kU32, v.size(), v.data(), v.size() * sizeof(std::uint32_t));
}
void CheckpointWriter::put(const std::string& name, const std::vector<std::uint8_t>& v) {
  record(name, kU8, v.size(), v.data(), v.size());
}
void CheckpointWriter::put(const std::string& name, double v) {
  const std::vector<double> a{v};
  put(name, a);
}
void CheckpointWriter::put(const std::string& name, std::int64_t v) { record(name, kI64, 1, &v, sizeof v); }
void CheckpointWriter::put(const std::string& name, const std::string& text) {
  record(name, kText, text.size(), text.data(), text.size());
}

void CheckpointWriter::commit() {
  const std::uint64_t h = hash_.value();
  record("end", kI64, 1, &h, sizeof h);
  if (std::fflush(f_) != 0) fail("cannot write");
  if (::fsync(::fileno(f_)) != 0) fail("cannot sync");
  if (std::fclose(f_) != 0) {
    f_ = nullptr;
    fail("cannot close");
  }
  f_ = nullptr;
  std::error_code ec;
  std::filesystem::rename(tmp_, file_, ec);
  if (ec) {
    std::filesystem::remove(tmp_, ec);
    throw CheckpointError("cannot rename checkpoint " + tmp_.string() + " to " + file_.string() + ": " + ec.message());
  }
  committed_ = true;
  fsync_path(file_.parent_path());
}

// ---------------------------------------------------------------------------------------------
CheckpointReader::CheckpointReader(std::filesystem::path file) : file_(std::move(file)) {
  f_ = std::fopen(file_.c_str(), "rb");
  if (!f_) throw CheckpointError("cannot open checkpoint " + file_.string() + ": " + errno_text());
  const auto bad = [&](const std::string& why) {
    std::fclose(f_);
    f_ = nullptr;
    return CheckpointError("checkpoint " + file_.string() + " is not a whole shockmpm checkpoint: " + why);
  };
  StreamHash hash;
  char magic[8];
  if (std::fread(magic, 1, 8, f_) != 8 || std::memcmp(magic, kMagic, 8) != 0) throw bad("no SMPMCKP1 header");
  hash.update(magic, 8);
  std::vector<char> chunk(1 << 20);
  const auto size = static_cast<long>(std::filesystem::file_size(file_));
  for (;;) {
    std::uint32_t len;
    if (std::fread(&len, sizeof len, 1, f_) != 1) throw bad("cut short (no end record)");
    if (len == 0 || len > 4096) throw bad("a record name of length " + std::to_string(len));
    std::string name(len, '\0');
    std::uint8_t type;
    std::uint64_t count;
    if (std::fread(name.data(), 1, len, f_) != len || std::fread(&type, 1, 1, f_) != 1 ||
        std::fread(&count, sizeof count, 1, f_) != 1)
      throw bad("cut short in a record header");
    const std::size_t es = type_size(type);
    if (es == 0) throw bad("record '" + name + "' of unknown type " + std::to_string(type));
    const long offset = std::ftell(f_);
    if (count > static_cast<std::uint64_t>(size - offset) / es) throw bad("record '" + name + "' runs past the end");
    if (name == "end") {
      std::uint64_t stored;
      if (type != kI64 || count != 1 || std::fread(&stored, 8, 1, f_) != 1) throw bad("a malformed end record");
      // the hash covers every byte before the end record
      if (hash.value() != stored) throw bad("its hash does not match its contents (damaged)");
      break;
    }
    hash.update(&len, sizeof len);
    hash.update(name.data(), len);
    hash.update(&type, 1);
    hash.update(&count, sizeof count);
    for (std::uint64_t left = count * es; left > 0;) {
      const std::size_t k = static_cast<std::size_t>(std::min<std::uint64_t>(left, chunk.size()));
      if (std::fread(chunk.data(), 1, k, f_) != k) throw bad("cut short in record '" + name + "'");
      hash.update(chunk.data(), k);
      left -= k;
    }
    index_[name] = Entry{type, count, offset};
  }
}

CheckpointReader::~CheckpointReader() {
  if (f_) std::fclose(f_);
}

const CheckpointReader::Entry& CheckpointReader::find(const std::string& name, std::uint8_t type) const {
  const auto it = index_.find(name);
  if (it == index_.end()) throw CheckpointError("checkpoint " + file_.string() + " has no record '" + name + "'");
  if (it->second.type != type)
    throw CheckpointError("checkpoint " + file_.string() + ": record '" + name + "' is a " +
                          kTypeName[it->second.type] + ", expected a " + kTypeName[type]);
  return it->second;
}

void CheckpointReader::read(const Entry& e, void* data, std::size_t bytes) const {
  if (bytes == 0) return;
  if (std::fseek(f_, e.offset, SEEK_SET) != 0 || std::fread(data, 1, bytes, f_) != bytes)
    throw CheckpointError("cannot read checkpoint " + file_.string() + ": " + errno_text());
}

void CheckpointReader::get(const std::string& name, std::vector<double>& v) const {
  const Entry& e = find(name, kDouble);
  v.resize(e.count);
  read(e, v.data(), v.size() * sizeof(double));
}
void CheckpointReader::get(const std::string& name, std::vector<std::uint32_t>& v) const {
  const Entry& e = find(name, kU32);
  v.resize(e.count);
  read(e, v.data(), v.size() * sizeof(std::uint32_t));
}
void CheckpointReader::get(const std::string& name, std::vector<std::uint8_t>& v) const {
  const Entry& e = find(name, kU8);
  v.resize(e.count);
  read(e, v.data(), v.size());
}
double CheckpointReader::number(const std::string& name) const {
  std::vector<double> v;
  get(name, v);
  if (v.size() != 1) throw CheckpointError("checkpoint " + file_.string() + ": record '" + name + "' is not one number");
  return v[0];
}
std::int64_t CheckpointReader::integer(const std::string& name) const {
  const Entry& e = find(name, kI64);
  std::int64_t v = 0;
  read(e, &v, sizeof v);
  return v;
}
std::string CheckpointReader::text(const std::string& name) const {
  const Entry& e = find(name, kText);
  std::string s(e.count, '\0');
  read(e, s.data(), s.size());
  return s;
}

// ---------------------------------------------------------------------------------------------
std::filesystem::path checkpoint_path(const std::filesystem::path& out_dir, long step) {
  char b[32];
  std::snprintf(b, sizeof b, "ckpt_%010ld.bin", step);
  return out_dir / "checkpoint" / b;
}

std::vector<std::filesystem::path> list_checkpoints(const std::filesystem::path& out_dir) {
  std::vector<std::filesystem::path> v;
  std::error_code ec;
  const auto dir = out_dir / "checkpoint";
  if (!std::filesystem::is_directory(dir, ec)) return v;
  for (const auto& f : std::filesystem::directory_iterator(dir)) {
    const auto name = f.path().filename().string();
    if (name.size() == 19 && name.rfind("ckpt_", 0) == 0 && f.path().extension() == ".bin") v.push_back(f.path());
  }
  std::sort(v.begin(), v.end());  // zero-padded step: name order is step order
  return v;
}

}  // namespace smpm
