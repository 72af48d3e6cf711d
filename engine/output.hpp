// Particle snapshots: one HDF5 file per output step plus an XDMF index that opens the whole
// series in ParaView.
//
// Layout of fields_dir/snap_<step, 8 digits>.h5 (all values double, SI units):
//   /particles/<name>        one dataset per field:
//                              scalar            shape {n}
//                              "position"        shape {n, 2} (x, y) or {n, 3} (x, y, z)
//                              a 3-component vector shape {n, 3}
//                              a 2-component vector shape {n, 3} (x, y, 0): the z column is
//                                                written as zeros so that ParaView sees a
//                                                3-component Vector (both its XDMF readers
//                                                want 3 components)
//                              a symmetric tensor shape {n, 6} in XDMF's Tensor6 order: xx, xy,
//                                                xz, yy, yz, zz
//                            string attribute "units" on each dataset
//   /particles               attributes "time" (double, s) and "step" (int64)
//   /topology/polyvertex     vertex indices 0..n-1 (int32, or int64 when n > 2^31 - 1): the
//                            Polyvertex connectivity. ParaView's Xdmf3 reader makes no cells for a
//                            Topology without a DataItem, and then nothing is drawn.
//
// fields_dir/particles.xdmf lists every snapshot written by this writer as a temporal collection
// (one Uniform grid per snapshot with its own n, Polyvertex topology, Geometry XY or XYZ from
// "position", every other field a Node-centred Scalar, Vector or Tensor6 attribute). It is rewritten after every
// snapshot by writing particles.xdmf.tmp and renaming it; snapshot files are written the same way
// (snap_*.h5.tmp, then rename), so a crash never leaves a truncated file under the final name.
//
// Errors: HDF5's automatic error printing is switched off while write() runs; any HDF5 or file
// system failure throws std::runtime_error naming the file, the failing call and HDF5's innermost
// error message. Invalid arguments (no 2- or 3-component "position", data size != n * components,
// components not 1, 2, 3 or 6, empty / duplicate names or names outside [A-Za-z0-9_.-]) throw
// std::invalid_argument before anything is written.
#pragma once
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace smpm {

struct SnapshotField {
  std::string name;          // dataset name, e.g. "position", "velocity", "pressure"
  std::string units;         // e.g. "m", "m/s", "Pa" (string attribute "units")
  int components = 1;        // 1 (scalar), 2 or 3 (vector), 6 (symmetric tensor); interleaved in `data`
  std::vector<double> data;  // n * components values
};

class SnapshotWriter {
 public:
  // Creates fields_dir (and its parents) if needed. The XDMF index lists only the snapshots
  // written through this object.
  explicit SnapshotWriter(std::filesystem::path fields_dir);

  // Writes fields_dir/snap_<step>.h5 and rewrites fields_dir/particles.xdmf (see above). `fields`
  // must contain "position" with 2 or 3 components. Writing a step again replaces that snapshot.
  void write(const std::vector<SnapshotField>& fields, std::size_t n, double time_s, long step);

  // The index (what particles.xdmf lists) as text, for a checkpoint; adopt() takes such a text
  // back when a run resumes: the index becomes that list, particles.xdmf is rewritten and the
  // snapshot files of the directory it does not list (written after the checkpoint) are removed.
  std::string index_text() const;
  void adopt(const std::string& index_text);

  // Snapshot files written so far, in the order first written.
  const std::vector<std::filesystem::path>& files() const { return files_; }

  const std::filesystem::path& dir() const { return dir_; }
  std::filesystem::path xdmf_path() const { return dir_ / "particles.xdmf"; }

 private:
  struct FieldInfo {
    std::string name;
    int components;
  };
  struct Entry {
    std::string file;  // file name relative to dir_
    long step;
    double time;
    std::size_t n;
    bool index64;  // topology indices stored as int64
    std::vector<FieldInfo> fields;
  };

  void write_xdmf() const;

  std::filesystem::path dir_;
  std::vector<std::filesystem::path> files_;
  std::vector<Entry> entries_;
};

// Writes a table as one HDF5 file: group /<group> with one 1D double dataset per column and a
// string attribute per entry of `attributes` (written to a temporary file, then renamed).
void write_table_h5(const std::filesystem::path& file, const std::string& group,
                    const std::vector<std::string>& columns, const std::vector<std::vector<double>>& data,
                    const std::vector<std::pair<std::string, std::string>>& attributes);

}  // namespace smpm
