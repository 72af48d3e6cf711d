// Particle snapshot writer: HDF5 contents read back with the C API, the XDMF index checked
// against the datasets it points to, and error handling (exceptions, no HDF5 error printing).
#include <catch2/catch.hpp>

#include <hdf5.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "engine/output.hpp"

namespace fs = std::filesystem;
using smpm::SnapshotField;
using smpm::SnapshotWriter;

namespace {

// A fresh directory under the system temp dir, removed at scope exit.
struct TempDir {
  fs::path path;
  TempDir() {
    std::string tmpl = (fs::temp_directory_path() / "smpm_test_output_XXXXXX").string();
    REQUIRE(mkdtemp(tmpl.data()) != nullptr);
    path = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

// Minimal RAII for the test's own HDF5 reads.
struct Id {
  hid_t id;
  herr_t (*closer)(hid_t);
  Id(hid_t i, herr_t (*c)(hid_t)) : id(i), closer(c) { REQUIRE(id >= 0); }
  ~Id() {
    if (id >= 0) closer(id);
  }
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
};

std::vector<hsize_t> dataset_dims(hid_t file, const std::string& path) {
  Id d(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose);
  Id s(H5Dget_space(d.id), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(s.id);
  REQUIRE(rank >= 1);
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  H5Sget_simple_extent_dims(s.id, dims.data(), nullptr);
  return dims;
}

std::vector<double> read_doubles(hid_t file, const std::string& path) {
  Id d(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose);
  Id t(H5Dget_type(d.id), H5Tclose);
  REQUIRE(H5Tget_class(t.id) == H5T_FLOAT);
  REQUIRE(H5Tget_size(t.id) == 8);
  Id s(H5Dget_space(d.id), H5Sclose);
  const auto npoints = H5Sget_simple_extent_npoints(s.id);
  std::vector<double> v(static_cast<std::size_t>(npoints));
  if (!v.empty()) REQUIRE(H5Dread(d.id, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) >= 0);
  return v;
}

std::vector<std::int64_t> read_ints(hid_t file, const std::string& path) {
  Id d(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose);
  Id t(H5Dget_type(d.id), H5Tclose);
  REQUIRE(H5Tget_class(t.id) == H5T_INTEGER);
  Id s(H5Dget_space(d.id), H5Sclose);
  std::vector<std::int64_t> v(static_cast<std::size_t>(H5Sget_simple_extent_npoints(s.id)));
  if (!v.empty()) REQUIRE(H5Dread(d.id, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) >= 0);
  return v;
}

std::string read_string_attr(hid_t obj, const char* name) {
  Id a(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
  Id t(H5Aget_type(a.id), H5Tclose);
  REQUIRE(H5Tget_class(t.id) == H5T_STRING);
  REQUIRE(H5Tis_variable_str(t.id) == 0);
  std::string buf(H5Tget_size(t.id), '\0');
  REQUIRE(H5Aread(a.id, t.id, buf.data()) >= 0);
  return std::string(buf.c_str());  // up to the NUL terminator
}

std::string dataset_units(hid_t file, const std::string& path) {
  Id d(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose);
  return read_string_attr(d.id, "units");
}

std::vector<std::string> dataset_names(hid_t file, const char* group) {
  Id g(H5Gopen2(file, group, H5P_DEFAULT), H5Gclose);
  H5G_info_t info;
  REQUIRE(H5Gget_info(g.id, &info) >= 0);
  std::vector<std::string> names;
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    const ssize_t len = H5Lget_name_by_idx(g.id, ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
    REQUIRE(len > 0);
    std::string name(static_cast<std::size_t>(len) + 1, '\0');
    H5Lget_name_by_idx(g.id, ".", H5_INDEX_NAME, H5_ITER_INC, i, name.data(), name.size(), H5P_DEFAULT);
    name.resize(static_cast<std::size_t>(len));
    names.push_back(name);
  }
  return names;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  REQUIRE(in.good());
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Value of attribute `key` inside an XML start tag's text ("" if absent).
std::string xml_attr(const std::string& tag, const std::string& key) {
  std::smatch m;
  const std::regex re("\\b" + key + "=\"([^\"]*)\"");
  return std::regex_search(tag, m, re) ? m[1].str() : std::string();
}

std::string join_dims(const std::vector<hsize_t>& dims) {
  std::string s;
  for (std::size_t i = 0; i < dims.size(); ++i) {
    if (i > 0) s += ' ';
    s += std::to_string(dims[i]);
  }
  return s;
}

struct Snap {
  std::size_t n;
  double time;
  long step;
  std::vector<SnapshotField> fields;
};

// A snapshot of n points over `axes` axes: position and velocity with `axes` components,
// pressure, with 3 axes a symmetric tensor (Tensor6), optionally a temperature.
Snap make_snapshot(std::size_t n, double time, long step, bool with_temperature, int axes = 2) {
  Snap s{n, time, step, {}};
  SnapshotField pos{"position", "m", axes, {}}, vel{"velocity", "m/s", axes, {}}, p{"pressure", "Pa", 1, {}};
  for (std::size_t i = 0; i < n; ++i) {
    pos.data.push_back(1e-3 * static_cast<double>(i));
    pos.data.push_back(-2e-3 * static_cast<double>(i) + static_cast<double>(step));
    vel.data.push_back(100.0 + static_cast<double>(i));
    vel.data.push_back(-50.0 - static_cast<double>(i) - 0.5 * static_cast<double>(step));
    if (axes == 3) {
      pos.data.push_back(3e-3 * static_cast<double>(i));
      vel.data.push_back(7.0 * static_cast<double>(i));
    }
    p.data.push_back(1e9 * static_cast<double>(i + 1) + static_cast<double>(step));
  }
  s.fields = {pos, vel, p};
  if (axes == 3) {
    SnapshotField t{"stress", "Pa", 6, {}};
    for (std::size_t i = 0; i < 6 * n; ++i) t.data.push_back(-1e8 * static_cast<double>(i));
    s.fields.push_back(t);
  }
  if (with_temperature) {
    SnapshotField T{"temperature", "K", 1, {}};
    for (std::size_t i = 0; i < n; ++i) T.data.push_back(300.0 + static_cast<double>(i));
    s.fields.push_back(T);
  }
  return s;
}

void check_snapshot_file(const fs::path& file, const Snap& s) {
  Id f(H5Fopen(file.string().c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  Id g(H5Gopen2(f.id, "/particles", H5P_DEFAULT), H5Gclose);
  {
    Id a(H5Aopen(g.id, "time", H5P_DEFAULT), H5Aclose);
    Id t(H5Aget_type(a.id), H5Tclose);
    CHECK(H5Tget_class(t.id) == H5T_FLOAT);
    CHECK(H5Tget_size(t.id) == 8);
    double time = -1;
    REQUIRE(H5Aread(a.id, H5T_NATIVE_DOUBLE, &time) >= 0);
    CHECK(time == s.time);
  }
  {
    Id a(H5Aopen(g.id, "step", H5P_DEFAULT), H5Aclose);
    Id t(H5Aget_type(a.id), H5Tclose);
    CHECK(H5Tget_class(t.id) == H5T_INTEGER);
    CHECK(H5Tget_size(t.id) == 8);
    CHECK(H5Tget_sign(t.id) == H5T_SGN_2);
    std::int64_t step = -1;
    REQUIRE(H5Aread(a.id, H5T_NATIVE_INT64, &step) >= 0);
    CHECK(step == s.step);
  }
  std::set<std::string> expected_names;
  for (const SnapshotField& fld : s.fields) {
    expected_names.insert(fld.name);
    const std::string path = "/particles/" + fld.name;
    const auto dims = dataset_dims(f.id, path);
    const auto v = read_doubles(f.id, path);
    CHECK(dataset_units(f.id, path) == fld.units);
    if (fld.components == 1) {
      REQUIRE(dims == std::vector<hsize_t>{s.n});
      for (std::size_t i = 0; i < s.n; ++i) CHECK(v[i] == fld.data[i]);
    } else if (fld.name == "position" || fld.components > 2) {  // as given
      const auto c = static_cast<std::size_t>(fld.components);
      REQUIRE(dims == std::vector<hsize_t>{s.n, c});
      for (std::size_t i = 0; i < c * s.n; ++i) CHECK(v[i] == fld.data[i]);
    } else {  // other 2-component vectors are stored (x, y, 0)
      REQUIRE(dims == std::vector<hsize_t>{s.n, 3});
      for (std::size_t i = 0; i < s.n; ++i) {
        CHECK(v[3 * i] == fld.data[2 * i]);
        CHECK(v[3 * i + 1] == fld.data[2 * i + 1]);
        CHECK(v[3 * i + 2] == 0.0);
      }
    }
  }
  const auto names = dataset_names(f.id, "/particles");
  CHECK(std::set<std::string>(names.begin(), names.end()) == expected_names);
  const auto idx = read_ints(f.id, "/topology/polyvertex");
  REQUIRE(idx.size() == s.n);
  for (std::size_t i = 0; i < s.n; ++i) CHECK(idx[i] == static_cast<std::int64_t>(i));
}

// Redirects the process's stderr (fd 2) into a temp file while alive; text() returns what was
// written.
class CaptureStderr {
 public:
  explicit CaptureStderr(const fs::path& file) : file_(file) {
    std::fflush(stderr);
    saved_ = dup(2);
    FILE* f = std::fopen(file.string().c_str(), "w");
    REQUIRE(f != nullptr);
    dup2(fileno(f), 2);
    std::fclose(f);
  }
  ~CaptureStderr() { restore(); }
  std::string text() {
    restore();
    return slurp(file_);
  }

 private:
  void restore() {
    if (saved_ >= 0) {
      std::fflush(stderr);
      dup2(saved_, 2);
      close(saved_);
      saved_ = -1;
    }
  }
  fs::path file_;
  int saved_ = -1;
};

}  // namespace

TEST_CASE("SnapshotWriter writes HDF5 snapshots and an XDMF temporal series", "[output]") {
  // 2D (Geometry XY, 2-component vectors padded to 3) and 3D (XYZ, 3-component vectors, Tensor6)
  const int axes = GENERATE(2, 3);
  INFO("axes " << axes);
  TempDir tmp;
  const fs::path dir = tmp.path / "out" / "fields";  // nested: the writer creates it
  SnapshotWriter w(dir);
  REQUIRE(fs::is_directory(dir));
  CHECK(w.files().empty());

  // Particle count and field set change between snapshots.
  const std::vector<Snap> snaps = {make_snapshot(3, 1.5e-7, 10, false, axes),
                                   make_snapshot(5, 3.25e-7, 20, true, axes)};
  for (const Snap& s : snaps) w.write(s.fields, s.n, s.time, s.step);

  REQUIRE(w.files().size() == 2);
  CHECK(w.files()[0] == dir / "snap_00000010.h5");
  CHECK(w.files()[1] == dir / "snap_00000020.h5");
  for (std::size_t k = 0; k < snaps.size(); ++k) check_snapshot_file(w.files()[k], snaps[k]);

  // Only the final files are left behind (no *.tmp).
  std::set<std::string> entries;
  for (const auto& de : fs::directory_iterator(dir)) entries.insert(de.path().filename().string());
  CHECK(entries == std::set<std::string>{"snap_00000010.h5", "snap_00000020.h5", "particles.xdmf"});

  // --- XDMF: structure, times, and every DataItem against the dataset it names ---------------
  const std::string xml = slurp(dir / "particles.xdmf");
  CHECK(xml.find("<Xdmf") != std::string::npos);
  CHECK(xml.find("CollectionType=\"Temporal\"") != std::string::npos);
  const std::regex grid_re("<Grid ([^>]*GridType=\"Uniform\"[^>]*)>([\\s\\S]*?)</Grid>");
  std::vector<std::string> grids;
  for (std::sregex_iterator it(xml.begin(), xml.end(), grid_re), end; it != end; ++it) {
    grids.push_back((*it)[2].str());
  }
  REQUIRE(grids.size() == 2);

  const std::regex item_re("<DataItem([^>]*)>([^<]*)</DataItem>");
  const std::regex time_re("<Time Value=\"([^\"]*)\"");
  for (std::size_t k = 0; k < grids.size(); ++k) {
    const std::string& g = grids[k];
    const Snap& s = snaps[k];
    INFO("grid " << k);
    std::smatch tm;
    REQUIRE(std::regex_search(g, tm, time_re));
    CHECK(std::stod(tm[1].str()) == s.time);

    std::smatch topo;
    REQUIRE(std::regex_search(g, topo, std::regex("<Topology([^>]*)>")));
    CHECK(xml_attr(topo[1].str(), "TopologyType") == "Polyvertex");
    CHECK(xml_attr(topo[1].str(), "NumberOfElements") == std::to_string(s.n));
    std::smatch geo;
    REQUIRE(std::regex_search(g, geo, std::regex("<Geometry([^>]*)>\\s*<DataItem[^>]*>([^<]*)</DataItem>")));
    CHECK(xml_attr(geo[1].str(), "GeometryType") == (axes == 3 ? "XYZ" : "XY"));
    CHECK(geo[2].str().find(":/particles/position") != std::string::npos);

    // Attributes: every field but position, with the right type.
    std::map<std::string, std::string> attr_types;
    const std::regex attr_re("<Attribute([^>]*)>\\s*<DataItem[^>]*>([^<]*)</DataItem>");
    for (std::sregex_iterator it(g.begin(), g.end(), attr_re), end; it != end; ++it) {
      const std::string tag = (*it)[1].str();
      const std::string name = xml_attr(tag, "Name");
      CHECK(xml_attr(tag, "Center") == "Node");
      CHECK((*it)[2].str().find(":/particles/" + name) != std::string::npos);
      attr_types[name] = xml_attr(tag, "AttributeType");
    }
    std::map<std::string, std::string> expected_types;
    for (const SnapshotField& f : s.fields) {
      if (f.name != "position")
        expected_types[f.name] = f.components == 1 ? "Scalar" : f.components == 6 ? "Tensor6" : "Vector";
    }
    CHECK(attr_types == expected_types);

    // Every DataItem: its file, path, Dimensions, number type and precision match the HDF5 data.
    int n_items = 0;
    for (std::sregex_iterator it(g.begin(), g.end(), item_re), end; it != end; ++it, ++n_items) {
      const std::string tag = (*it)[1].str();
      const std::string ref = (*it)[2].str();
      INFO("DataItem " << tag << " -> " << ref);
      CHECK(xml_attr(tag, "Format") == "HDF");
      const auto colon = ref.find(':');
      REQUIRE(colon != std::string::npos);
      const std::string file = ref.substr(0, colon), path = ref.substr(colon + 1);
      CHECK(dir / file == w.files()[k]);
      Id f(H5Fopen((dir / file).string().c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
      CHECK(xml_attr(tag, "Dimensions") == join_dims(dataset_dims(f.id, path)));
      Id d(H5Dopen2(f.id, path.c_str(), H5P_DEFAULT), H5Dclose);
      Id t(H5Dget_type(d.id), H5Tclose);
      CHECK(xml_attr(tag, "NumberType") == (H5Tget_class(t.id) == H5T_FLOAT ? "Float" : "Int"));
      CHECK(xml_attr(tag, "Precision") == std::to_string(H5Tget_size(t.id)));
    }
    // topology + geometry + one per attribute
    CHECK(n_items == 2 + static_cast<int>(expected_types.size()));
  }

  // Writing a step again replaces it (same file, one entry in the series).
  Snap again = make_snapshot(4, 1.5e-7, 10, false, axes);
  w.write(again.fields, again.n, again.time, again.step);
  CHECK(w.files().size() == 2);
  check_snapshot_file(dir / "snap_00000010.h5", again);
  const std::string xml2 = slurp(dir / "particles.xdmf");
  std::size_t n_grids = 0;
  for (std::sregex_iterator it(xml2.begin(), xml2.end(), grid_re), end; it != end; ++it) ++n_grids;
  CHECK(n_grids == 2);
  CHECK(xml2.find("NumberOfElements=\"4\"") != std::string::npos);
}

TEST_CASE("SnapshotWriter rejects malformed input before writing", "[output]") {
  TempDir tmp;
  SnapshotWriter w(tmp.path / "fields");
  const Snap ok = make_snapshot(3, 0.0, 0, false);

  auto without_position = ok.fields;
  without_position.erase(without_position.begin());
  CHECK_THROWS_AS(w.write(without_position, 3, 0.0, 0), std::invalid_argument);

  auto wrong_size = ok.fields;
  wrong_size[2].data.pop_back();
  CHECK_THROWS_AS(w.write(wrong_size, 3, 0.0, 0), std::invalid_argument);

  auto bad_components = ok.fields;
  bad_components[2].components = 4;  // 1, 2, 3 or 6 allowed
  CHECK_THROWS_AS(w.write(bad_components, 3, 0.0, 0), std::invalid_argument);

  auto duplicate = ok.fields;
  duplicate.push_back(duplicate[2]);
  CHECK_THROWS_AS(w.write(duplicate, 3, 0.0, 0), std::invalid_argument);

  auto bad_name = ok.fields;
  bad_name[2].name = "a/b";
  CHECK_THROWS_AS(w.write(bad_name, 3, 0.0, 0), std::invalid_argument);

  CHECK_THROWS_AS(w.write(ok.fields, 3, 0.0, -1), std::invalid_argument);
  CHECK(w.files().empty());
  CHECK(fs::is_empty(tmp.path / "fields"));
}

TEST_CASE("SnapshotWriter turns HDF5 failures into exceptions without printing", "[output]") {
  TempDir tmp;
  const fs::path dir = tmp.path / "fields";
  SnapshotWriter w(dir);
  const Snap s = make_snapshot(3, 1.0, 7, false);
  fs::remove_all(dir);  // H5Fcreate will fail: no such directory

  H5E_auto2_t func_before = nullptr;
  void* data_before = nullptr;
  H5Eget_auto2(H5E_DEFAULT, &func_before, &data_before);

  std::string message;
  std::string printed;
  {
    CaptureStderr cap(tmp.path / "stderr.txt");
    try {
      w.write(s.fields, s.n, s.time, s.step);
    } catch (const std::runtime_error& e) {
      message = e.what();
    }
    printed = cap.text();
  }
  INFO("message: " << message);
  CHECK(message.find("H5Fcreate") != std::string::npos);
  CHECK(message.find((dir / "snap_00000007.h5").string()) != std::string::npos);
  CHECK(printed.empty());
  CHECK(w.files().empty());

  // The previous automatic error handler is back in place.
  H5E_auto2_t func_after = nullptr;
  void* data_after = nullptr;
  H5Eget_auto2(H5E_DEFAULT, &func_after, &data_after);
  CHECK(func_after == func_before);
  CHECK(data_after == data_before);
}
