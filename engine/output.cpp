#include "engine/output.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <utility>

namespace smpm {

namespace fs = std::filesystem;

namespace {

// ---------------------------------------------------------------------------------------------
// HDF5 error handling

// Switches off HDF5's automatic error-stack printing for its lifetime and restores the previous
// handler afterwards (other code in the process may rely on it).
class QuietHdf5 {
 public:
  QuietHdf5() {
    saved_ = H5Eget_auto2(H5E_DEFAULT, &func_, &data_) >= 0;
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    H5Eclear2(H5E_DEFAULT);
  }
  ~QuietHdf5() {
    if (saved_) H5Eset_auto2(H5E_DEFAULT, func_, data_);
  }
  QuietHdf5(const QuietHdf5&) = delete;
  QuietHdf5& operator=(const QuietHdf5&) = delete;

 private:
  H5E_auto2_t func_ = nullptr;
  void* data_ = nullptr;
  bool saved_ = false;
};

herr_t keep_innermost(unsigned /*n*/, const H5E_error2_t* err, void* client) {
  if (err != nullptr && err->desc != nullptr && err->desc[0] != '\0') {
    *static_cast<std::string*>(client) = err->desc;
  }
  return 0;
}

// The innermost message on HDF5's error stack (the root cause), then clears the stack.
std::string hdf5_detail() {
  std::string detail;
  // Downward walk: from the API call to the function where the error was detected; the last
  // message seen is the most specific one.
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, keep_innermost, &detail);
  H5Eclear2(H5E_DEFAULT);
  return detail;
}

[[noreturn]] void fail(const std::string& file, const char* call, const std::string& what) {
  std::string msg = "SnapshotWriter: ";
  msg += call;
  msg += " failed";
  if (!what.empty()) msg += " (" + what + ")";
  msg += " for file '" + file + "'";
  const std::string detail = hdf5_detail();
  if (!detail.empty()) msg += ": " + detail;
  throw std::runtime_error(msg);
}

// Owns one HDF5 identifier and closes it with the matching H5?close function.
class H5Id {
 public:
  using Closer = herr_t (*)(hid_t);
  H5Id() = default;
  H5Id(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  ~H5Id() { reset(); }
  H5Id(H5Id&& o) noexcept : id_(std::exchange(o.id_, H5I_INVALID_HID)), closer_(o.closer_) {}
  H5Id& operator=(H5Id&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = std::exchange(o.id_, H5I_INVALID_HID);
      closer_ = o.closer_;
    }
    return *this;
  }
  H5Id(const H5Id&) = delete;
  H5Id& operator=(const H5Id&) = delete;

  hid_t get() const { return id_; }
  // Closes now; returns the close function's status (negative on failure).
  herr_t close() {
    herr_t r = 0;
    if (id_ >= 0 && closer_ != nullptr) r = closer_(id_);
    id_ = H5I_INVALID_HID;
    return r;
  }
  void reset() noexcept { (void)close(); }

 private:
  hid_t id_ = H5I_INVALID_HID;
  Closer closer_ = nullptr;
};

// Error context for one HDF5 file.
struct H5File {
  std::string name;

  H5Id own(hid_t id, H5Id::Closer closer, const char* call, const std::string& what = {}) const {
    if (id < 0) fail(name, call, what);
    return H5Id(id, closer);
  }
  void check(herr_t status, const char* call, const std::string& what = {}) const {
    if (status < 0) fail(name, call, what);
  }

  void scalar_attribute(hid_t loc, const char* attr, hid_t file_type, hid_t mem_type,
                        const void* value) const {
    const std::string what = std::string("attribute ") + attr;
    H5Id space = own(H5Screate(H5S_SCALAR), H5Sclose, "H5Screate", what);
    H5Id a = own(H5Acreate2(loc, attr, file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
                 "H5Acreate2", what);
    check(H5Awrite(a.get(), mem_type, value), "H5Awrite", what);
    check(a.close(), "H5Aclose", what);
  }

  void string_attribute(hid_t loc, const char* attr, const std::string& value,
                        const std::string& where) const {
    const std::string what = std::string("attribute ") + attr + " of " + where;
    // Fixed-length, NUL-terminated UTF-8 string (size includes the terminator, so never 0).
    H5Id type = own(H5Tcopy(H5T_C_S1), H5Tclose, "H5Tcopy", what);
    check(H5Tset_size(type.get(), value.size() + 1), "H5Tset_size", what);
    check(H5Tset_strpad(type.get(), H5T_STR_NULLTERM), "H5Tset_strpad", what);
    check(H5Tset_cset(type.get(), H5T_CSET_UTF8), "H5Tset_cset", what);
    H5Id space = own(H5Screate(H5S_SCALAR), H5Sclose, "H5Screate", what);
    H5Id a = own(H5Acreate2(loc, attr, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
                 H5Aclose, "H5Acreate2", what);
    check(H5Awrite(a.get(), type.get(), value.c_str()), "H5Awrite", what);
    check(a.close(), "H5Aclose", what);
  }

  // An object creation property list without modification times: the same data give the same
  // file, byte for byte (a resumed run's snapshots equal an uninterrupted run's).
  H5Id untimed(hid_t cls, const std::string& what) const {
    H5Id p = own(H5Pcreate(cls), H5Pclose, "H5Pcreate", what);
    check(H5Pset_obj_track_times(p.get(), 0), "H5Pset_obj_track_times", what);
    return p;
  }

  // Creates dataset `path` (relative to loc) of the given shape and writes `data` (may be null
  // when the dataset is empty).
  H5Id dataset(hid_t loc, const char* path, const hsize_t* dims, int rank, hid_t file_type,
               hid_t mem_type, const void* data, const std::string& what) const {
    H5Id space = own(H5Screate_simple(rank, dims, nullptr), H5Sclose, "H5Screate_simple", what);
    H5Id dcpl = untimed(H5P_DATASET_CREATE, what);
    H5Id d = own(H5Dcreate2(loc, path, file_type, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
                 H5Dclose, "H5Dcreate2", what);
    if (dims[0] > 0) {
      check(H5Dwrite(d.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), "H5Dwrite", what);
    }
    return d;
  }
};

template <class Int>
std::vector<Int> iota_indices(std::size_t n) {
  std::vector<Int> v(n);
  std::iota(v.begin(), v.end(), Int{0});
  return v;
}

// Writes one complete snapshot file at `path`.
void write_snapshot_file(const fs::path& path, const std::vector<SnapshotField>& fields, std::size_t n,
                         double time_s, long step, bool index64) {
  const H5File f{path.string()};
  H5Id file = f.own(H5Fcreate(f.name.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose,
                    "H5Fcreate");
  {
    H5Id grp = f.own(H5Gcreate2(file.get(), "/particles", H5P_DEFAULT, f.untimed(H5P_GROUP_CREATE, "group /particles").get(), H5P_DEFAULT),
                     H5Gclose, "H5Gcreate2", "group /particles");
    const std::int64_t step64 = step;
    f.scalar_attribute(grp.get(), "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &time_s);
    f.scalar_attribute(grp.get(), "step", H5T_STD_I64LE, H5T_NATIVE_INT64, &step64);

    std::vector<double> padded;
    for (const SnapshotField& fld : fields) {
      const std::string what = "dataset /particles/" + fld.name;
      hsize_t dims[2] = {static_cast<hsize_t>(n), 0};
      int rank = 1;
      const double* data = fld.data.data();
      if (fld.components > 1) {
        rank = 2;
        dims[1] = static_cast<hsize_t>(fld.components);  // Geometry XY / XYZ, Vector, Tensor6 as given
        if (fld.components == 2 && fld.name != "position") {
          // ParaView wants 3-component vectors: store (x, y, 0).
          dims[1] = 3;
          padded.assign(3 * n, 0.0);
          for (std::size_t i = 0; i < n; ++i) {
            padded[3 * i] = fld.data[2 * i];
            padded[3 * i + 1] = fld.data[2 * i + 1];
          }
          data = padded.data();
        }
      }
      H5Id d = f.dataset(grp.get(), fld.name.c_str(), dims, rank, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE,
                         data, what);
      f.string_attribute(d.get(), "units", fld.units, what);
      f.check(d.close(), "H5Dclose", what);
    }
    f.check(grp.close(), "H5Gclose", "group /particles");
  }
  {
    const std::string what = "dataset /topology/polyvertex";
    H5Id grp = f.own(H5Gcreate2(file.get(), "/topology", H5P_DEFAULT, f.untimed(H5P_GROUP_CREATE, "group /topology").get(), H5P_DEFAULT),
                     H5Gclose, "H5Gcreate2", "group /topology");
    const hsize_t dims[1] = {static_cast<hsize_t>(n)};
    H5Id d;
    if (index64) {
      const auto idx = iota_indices<std::int64_t>(n);
      d = f.dataset(grp.get(), "polyvertex", dims, 1, H5T_STD_I64LE, H5T_NATIVE_INT64, idx.data(), what);
    } else {
      const auto idx = iota_indices<std::int32_t>(n);
      d = f.dataset(grp.get(), "polyvertex", dims, 1, H5T_STD_I32LE, H5T_NATIVE_INT32, idx.data(), what);
    }
    f.check(d.close(), "H5Dclose", what);
    f.check(grp.close(), "H5Gclose", "group /topology");
  }
  // Everything inside the file is closed, so this really closes (and flushes) it.
  f.check(file.close(), "H5Fclose");
}

void validate(const std::vector<SnapshotField>& fields, std::size_t n, double time_s, long step) {
  if (step < 0) throw std::invalid_argument("SnapshotWriter: negative step " + std::to_string(step));
  if (!std::isfinite(time_s)) throw std::invalid_argument("SnapshotWriter: time is not finite");
  bool have_position = false;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const SnapshotField& f = fields[i];
    const auto ok_char = [](char c) {
      return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
             c == '-' || c == '.';
    };
    if (f.name.empty() || f.name[0] == '.' || f.name[0] == '-' ||
        !std::all_of(f.name.begin(), f.name.end(), ok_char)) {
      throw std::invalid_argument("SnapshotWriter: invalid field name '" + f.name +
                                  "' (use letters, digits, '_', '-', '.'; not starting with '.' or '-')");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (fields[j].name == f.name) {
        throw std::invalid_argument("SnapshotWriter: duplicate field '" + f.name + "'");
      }
    }
    if (f.components != 1 && f.components != 2 && f.components != 3 && f.components != 6) {
      throw std::invalid_argument("SnapshotWriter: field '" + f.name + "' has " +
                                  std::to_string(f.components) + " components (1, 2, 3 or 6 allowed)");
    }
    if (f.data.size() != n * static_cast<std::size_t>(f.components)) {
      throw std::invalid_argument("SnapshotWriter: field '" + f.name + "' has " +
                                  std::to_string(f.data.size()) + " values, expected " +
                                  std::to_string(n) + " x " + std::to_string(f.components));
    }
    if (f.name == "position") {
      if (f.components != 2 && f.components != 3) {
        throw std::invalid_argument("SnapshotWriter: field 'position' must have 2 or 3 components");
      }
      have_position = true;
    }
  }
  if (!have_position) throw std::invalid_argument("SnapshotWriter: no 'position' field");
}

// Shortest representation that reads back to the same double.
std::string format_double(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string snapshot_name(long step) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "snap_%08ld.h5", step);
  return buf;
}

void remove_quietly(const fs::path& p) {
  std::error_code ec;
  fs::remove(p, ec);
}

void rename_or_throw(const fs::path& from, const fs::path& to) {
  std::error_code ec;
  fs::rename(from, to, ec);
  if (ec) {
    remove_quietly(from);
    throw std::runtime_error("SnapshotWriter: rename of '" + from.string() + "' to '" + to.string() +
                             "' failed: " + ec.message());
  }
}

}  // namespace

SnapshotWriter::SnapshotWriter(fs::path fields_dir) : dir_(std::move(fields_dir)) {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec || !fs::is_directory(dir_)) {
    throw std::runtime_error("SnapshotWriter: cannot create directory '" + dir_.string() +
                             "'" + (ec ? ": " + ec.message() : std::string()));
  }
}

void SnapshotWriter::write(const std::vector<SnapshotField>& fields, std::size_t n, double time_s,
                           long step) {
  validate(fields, n, time_s, step);

  Entry e;
  e.file = snapshot_name(step);
  e.step = step;
  e.time = time_s;
  e.n = n;
  e.index64 = n > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max());
  for (const SnapshotField& f : fields) e.fields.push_back({f.name, f.components});

  const fs::path final_path = dir_ / e.file;
  const fs::path tmp_path = dir_ / (e.file + ".tmp");
  {
    const QuietHdf5 quiet;  // outlives every handle opened below
    try {
      write_snapshot_file(tmp_path, fields, n, time_s, step, e.index64);
    } catch (...) {
      remove_quietly(tmp_path);
      throw;
    }
  }
  rename_or_throw(tmp_path, final_path);

  const auto same_step = std::find_if(entries_.begin(), entries_.end(),
                                      [&](const Entry& x) { return x.step == step; });
  if (same_step != entries_.end()) {
    *same_step = std::move(e);
  } else {
    entries_.push_back(std::move(e));
    files_.push_back(final_path);
  }
  write_xdmf();
}

std::string SnapshotWriter::index_text() const {
  std::ostringstream o;
  o.precision(17);
  for (const Entry& e : entries_) {
    o << e.file << ' ' << e.step << ' ' << e.time << ' ' << e.n << ' ' << e.index64 << ' ' << e.fields.size();
    for (const auto& f : e.fields) o << ' ' << f.name << ' ' << f.components;
    o << '\n';
  }
  return o.str();
}

void SnapshotWriter::adopt(const std::string& index_text) {
  std::vector<Entry> entries;
  std::istringstream in(index_text);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream l(line);
    Entry e;
    std::size_t nf = 0;
    l >> e.file >> e.step >> e.time >> e.n >> e.index64 >> nf;
    for (std::size_t k = 0; k < nf && l; ++k) {
      FieldInfo f;
      l >> f.name >> f.components;
      e.fields.push_back(f);
    }
    if (!l || e.file != snapshot_name(e.step))
      throw std::runtime_error("snapshot index of a checkpoint: unreadable entry '" + line + "'");
    entries.push_back(std::move(e));
  }
  entries_ = std::move(entries);
  files_.clear();
  for (const Entry& e : entries_) files_.push_back(dir_ / e.file);
  for (const auto& f : fs::directory_iterator(dir_)) {
    const auto name = f.path().filename().string();
    const bool listed = std::any_of(entries_.begin(), entries_.end(), [&](const Entry& e) { return e.file == name; });
    if (!listed && name.rfind("snap_", 0) == 0 && f.path().extension() == ".h5") fs::remove(f.path());
  }
  write_xdmf();
}

void SnapshotWriter::write_xdmf() const {
  std::string s;
  s.reserve(1024 + 2048 * entries_.size());
  s += "<?xml version=\"1.0\" ?>\n";
  s += "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n";
  s += "<Xdmf Version=\"3.0\">\n";
  s += "  <Domain>\n";
  s += "    <Grid Name=\"particles\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (const Entry& e : entries_) {
    const std::string n = std::to_string(e.n);
    const auto item = [&](const std::string& dims, const char* number_type, int precision,
                          const std::string& h5path) {
      s += "          <DataItem Dimensions=\"" + dims + "\" NumberType=\"" + number_type +
           "\" Precision=\"" + std::to_string(precision) + "\" Format=\"HDF\">" + e.file + ":" + h5path +
           "</DataItem>\n";
    };
    char grid_name[64];
    std::snprintf(grid_name, sizeof grid_name, "step_%08ld", e.step);
    s += "      <Grid Name=\"" + std::string(grid_name) + "\" GridType=\"Uniform\">\n";
    s += "        <Time Value=\"" + format_double(e.time) + "\"/>\n";
    s += "        <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" + n +
         "\" NodesPerElement=\"1\">\n";
    item(n, "Int", e.index64 ? 8 : 4, "/topology/polyvertex");
    s += "        </Topology>\n";
    int axes = 2;
    for (const FieldInfo& f : e.fields)
      if (f.name == "position") axes = f.components;
    s += std::string("        <Geometry GeometryType=\"") + (axes == 3 ? "XYZ" : "XY") + "\">\n";
    item(n + " " + std::to_string(axes), "Float", 8, "/particles/position");
    s += "        </Geometry>\n";
    for (const FieldInfo& f : e.fields) {
      if (f.name == "position") continue;
      // a 2-component vector is stored padded to 3 (x, y, 0)
      const char* type = f.components == 1 ? "Scalar" : f.components == 6 ? "Tensor6" : "Vector";
      const int stored = f.components == 2 ? 3 : f.components;
      s += "        <Attribute Name=\"" + f.name + "\" AttributeType=\"" + type + "\" Center=\"Node\">\n";
      item(stored == 1 ? n : n + " " + std::to_string(stored), "Float", 8, "/particles/" + f.name);
      s += "        </Attribute>\n";
    }
    s += "      </Grid>\n";
  }
  s += "    </Grid>\n";
  s += "  </Domain>\n";
  s += "</Xdmf>\n";

  const fs::path final_path = xdmf_path();
  const fs::path tmp_path = dir_ / "particles.xdmf.tmp";
  {
    std::ofstream out(tmp_path, std::ios::binary | std::ios::trunc);
    if (!out) {
      throw std::runtime_error("SnapshotWriter: cannot open '" + tmp_path.string() +
                               "' for writing: " + std::strerror(errno));
    }
    out.write(s.data(), static_cast<std::streamsize>(s.size()));
    out.close();
    if (!out) {
      remove_quietly(tmp_path);
      throw std::runtime_error("SnapshotWriter: writing '" + tmp_path.string() + "' failed");
    }
  }
  rename_or_throw(tmp_path, final_path);
}

void write_table_h5(const fs::path& file, const std::string& group, const std::vector<std::string>& columns,
                    const std::vector<std::vector<double>>& data,
                    const std::vector<std::pair<std::string, std::string>>& attributes) {
  if (columns.size() != data.size()) throw std::invalid_argument("write_table_h5: columns and data differ in size");
  QuietHdf5 quiet;
  const fs::path tmp = file.string() + ".tmp";
  {
    const H5File f{tmp.string()};
    H5Id h = f.own(H5Fcreate(f.name.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose, "H5Fcreate");
    const std::string gname = "/" + group;
    H5Id grp = f.own(H5Gcreate2(h.get(), gname.c_str(), H5P_DEFAULT, f.untimed(H5P_GROUP_CREATE, "group " + gname).get(), H5P_DEFAULT), H5Gclose,
                     "H5Gcreate2", "group " + gname);
    for (const auto& [k, v] : attributes) f.string_attribute(grp.get(), k.c_str(), v, "group " + gname);
    for (std::size_t c = 0; c < columns.size(); ++c) {
      const std::string what = "dataset " + gname + "/" + columns[c];
      const hsize_t dims[1] = {static_cast<hsize_t>(data[c].size())};
      H5Id d = f.dataset(grp.get(), columns[c].c_str(), dims, 1, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE,
                         data[c].data(), what);
      f.check(d.close(), "H5Dclose", what);
    }
    f.check(grp.close(), "H5Gclose", "group " + gname);
    f.check(h.close(), "H5Fclose");
  }
  rename_or_throw(tmp, file);
}

}  // namespace smpm
