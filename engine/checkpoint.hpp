// Checkpoint files: a run's whole state, from which `shockmpm resume` continues it bit for bit.
//
// Format (native byte order, little-endian on every supported machine):
//   "SMPMCKP1"                                       8 bytes
//   records: u32 name length, name, u8 type (1 double, 2 uint32, 3 uint8, 4 int64, 5 text),
//            u64 element count, the elements
//   the record "end" (type 4, one element: StreamHash of every byte before this record)
// A file is committed whole or not at all: written to NAME.tmp, fsync'ed, renamed, and the
// directory fsync'ed. The reader checks the magic and the hash before it hands out a record, so a
// file cut short or damaged is refused with its name, never half-read.
#pragma once
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace smpm {

// FNV-1a over 8-byte words (a last partial word padded with zeros, then its length mixed in):
// the same value for any split of the byte stream, about 8x the byte-wise speed.
class StreamHash {
 public:
  void update(const void* data, std::size_t n);
  std::uint64_t value() const;

 private:
  void mix(std::uint64_t w) { h_ = (h_ ^ w) * 0x100000001b3ULL; }
  std::uint64_t h_ = 0xcbf29ce484222325ULL;
  unsigned char buf_[8] = {};
  std::size_t fill_ = 0;
};

// A checkpoint that cannot be written (the run ends "failed", exit 1) or read (exit 2).
struct CheckpointError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class CheckpointWriter {
 public:
  // Opens file.tmp; commit() makes it `file`.
  explicit CheckpointWriter(std::filesystem::path file);
  ~CheckpointWriter();  // an uncommitted writer removes its .tmp file
  CheckpointWriter(const CheckpointWriter&) = delete;
  CheckpointWriter& operator=(const CheckpointWriter&) = delete;

  void put(const std::string& name, const std::vector<double>& v);
  void put(const std::string& name, const std::vector<std::uint32_t>& v);
  void put(const std::string& name, const std::vector<std::uint8_t>& v);
  void put(const std::string& name, double v);
  void put(const std::string& name, std::int64_t v);
  void put(const std::string& name, const std::string& text);
  // the hash record, fsync, rename to the final name, fsync of the directory
  void commit();

 private:
  void record(const std::string& name, std::uint8_t type, std::uint64_t count, const void* data, std::size_t bytes);
  void write(const void* data, std::size_t bytes);
  [[noreturn]] void fail(const std::string& what);

  std::filesystem::path file_, tmp_;
  std::FILE* f_ = nullptr;
  StreamHash hash_;
  bool committed_ = false;
};

class CheckpointReader {
 public:
  // Reads the record index and checks the hash (one pass over the file); throws
  // CheckpointError naming the file when it is not a whole checkpoint.
  explicit CheckpointReader(std::filesystem::path file);
  ~CheckpointReader();
  CheckpointReader(const CheckpointReader&) = delete;
  CheckpointReader& operator=(const CheckpointReader&) = delete;

  bool has(const std::string& name) const { return index_.count(name) != 0; }
  // Each throws CheckpointError naming the file and record when it is missing or of another type.
  void get(const std::string& name, std::vector<double>& v) const;
  void get(const std::string& name, std::vector<std::uint32_t>& v) const;
  void get(const std::string& name, std::vector<std::uint8_t>& v) const;
  double number(const std::string& name) const;
  std::int64_t integer(const std::string& name) const;
  std::string text(const std::string& name) const;
  const std::filesystem::path& file() const { return file_; }

 private:
  struct Entry {
    std::uint8_t type;
    std::uint64_t count;
    long offset;  // of the first element
  };
  const Entry& find(const std::string& name, std::uint8_t type) const;
  void read(const Entry& e, void* data, std::size_t bytes) const;

  std::filesystem::path file_;
  std::FILE* f_ = nullptr;
  std::map<std::string, Entry> index_;
};

// The checkpoints of an output directory (OUT/checkpoint/ckpt_<step>.bin), oldest first.
std::vector<std::filesystem::path> list_checkpoints(const std::filesystem::path& out_dir);
std::filesystem::path checkpoint_path(const std::filesystem::path& out_dir, long step);

}  // namespace smpm
