// The bird's-eye-view evidence grid of one atomic road (METHOD.md section 3): class evidence
// accumulated over many projected camera frames, in the map's ENU metres.
//
// Layers are absolute, not ego-relative. The segmentation's five lane classes (ego, left, right,
// left-left, right-right) name lanes relative to where the car was when the frame was taken, so
// they change meaning at every lane change. What stays true across frames is (a) that a pixel is
// drivable lane and (b) that two neighbouring pixels of *different* lane classes lie on a
// separation between two lanes, painted or not. The projector turns lane classes into kDrivable
// and lane-class transitions into kLaneSeparation; marking classes map to their own layer.
// Every projected pixel also counts in kObserved, so fraction() is "how often this cell was seen
// as that class when it was seen at all".
//
// Sparse: square tiles of tile_cells x tile_cells cells are allocated on first write, so a road's
// grid costs its corridor's area, not its bounding box's. Counts are uint16, saturating.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

namespace lanemap::bev {

enum class Layer : uint8_t {
  kObserved = 0,    // the cell was seen (any class, background included)
  kDrivable,        // any of the five lane classes
  kLaneSeparation,  // between two different lane classes (lane boundary, painted or not)
  kDashedLine,
  kSolidLine,
  kCrosswalk,
  kCurb,
  kStopLine,
  kCount
};
inline constexpr int kNumLayers = static_cast<int>(Layer::kCount);
const char* toString(Layer layer);

class BevError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct BevGridOptions {
  double resolution_m = 0.1;  // cell side
  int tile_cells = 128;       // tile side in cells (12.8 m at 0.1 m)
};

// A rigid move of a grid's cells: turned by rotation_rad (counter-clockwise: east towards north)
// about the cell `pivot`, then `shift` cells away. The turn is three shears (x += a y, y += b x,
// x += a y; a = -tan(rotation / 2), b = sin(rotation)), each rounded to whole cells, so each is a
// one-to-one map of cells and so is the move: every source cell lands on exactly one cell, none
// twice, and no count is lost or doubled. A cell lands within about a cell of where an exact turn
// would put it.
struct CellMove {
  Eigen::Vector2i shift = Eigen::Vector2i::Zero();
  double rotation_rad = 0.0;
  Eigen::Vector2i pivot = Eigen::Vector2i::Zero();
  bool identity() const { return rotation_rad == 0.0 && shift == Eigen::Vector2i::Zero(); }
  // The turn's shear factors (a, b): worked out once by a caller that moves many cells.
  Eigen::Vector2d shears() const { return {-std::tan(rotation_rad / 2), std::sin(rotation_rad)}; }
  Eigen::Vector2i apply(const Eigen::Vector2i& cell, const Eigen::Vector2d& shears) const;
  Eigen::Vector2i apply(const Eigen::Vector2i& cell) const { return apply(cell, shears()); }
};

class BevGrid {
 public:
  using Cell = Eigen::Vector2i;  // (column east, row north): cell (i, j) covers
                                 // [i*res, (i+1)*res) x [j*res, (j+1)*res) in ENU metres

  explicit BevGrid(BevGridOptions options = {});

  const BevGridOptions& options() const { return options_; }
  double resolution() const { return options_.resolution_m; }

  Cell cellOf(const Eigen::Vector2d& enu) const;
  Eigen::Vector2d cellCentre(const Cell& cell) const;

  // Adds `n` observations of `layer` to a cell (allocating its tile), saturating at 65535.
  void add(const Cell& cell, Layer layer, uint16_t n = 1);
  // Count of a layer in a cell; 0 where nothing was written.
  uint16_t count(const Cell& cell, Layer layer) const;
  uint16_t count(const Eigen::Vector2d& enu, Layer layer) const { return count(cellOf(enu), layer); }
  // count(layer) / count(kObserved); 0 for a cell never observed.
  float fraction(const Cell& cell, Layer layer) const;
  float fraction(const Eigen::Vector2d& enu, Layer layer) const { return fraction(cellOf(enu), layer); }
  bool observed(const Cell& cell) const { return count(cell, Layer::kObserved) > 0; }

  // Frames accumulated (kept by the caller through addFrame()).
  int frames() const { return frames_; }
  void addFrame() { ++frames_; }
  // Traversals (drives along the road) whose evidence the grid holds: a grid with frames that was
  // never merged (one drive's accumulation, a file of format 001) is one; bev_store.h mergeGrid
  // adds the source's to the destination's.
  int traversals() const { return traversals_ > 0 ? traversals_ : (frames_ > 0 ? 1 : 0); }
  void setTraversals(int n) { traversals_ = n; }
  // How well the traversals agreed: each merge of a traversal into evidence already there
  // (bev_align.h mergeAligned) adds its agreement, the alignment's correlation at its peak clipped
  // to [0, 1] (0 for a merge made unaligned). agreement() is their sum: a road driven once has 0,
  // one driven three times by drives that agree perfectly has 2 (lane confidence, issue 14).
  int merges() const { return merges_; }
  double agreement() const { return agreement_; }
  void addMerge(double agreement);  // clips to [0, 1]
  void addMerges(int merges, double agreement);  // another grid's, when its evidence joins this one

  // Cells spanned by the allocated tiles (empty box when none).
  Eigen::AlignedBox2i cellBounds() const;
  size_t tileCount() const { return tiles_.size(); }
  size_t memoryBytes() const;

  // Visits every allocated tile: origin cell (its min corner) and a pointer to its counts,
  // layer-major: counts[layer * tile_cells^2 + row * tile_cells + col].
  template <typename F>
  void forEachTile(F&& f) const {
    for (const auto& [key, tile] : tiles_) f(tileOrigin(key), tile.data());
  }

  // Binary file (little-endian): magic "LMBEV003", resolution, tile size, layers, frames,
  // traversals, merges, agreement, tiles. Written atomically (io::writeFileAtomically). load() also
  // reads formats 001 (no traversals) and 002 (no merges and agreement: read as none) of older
  // stores, and throws BevError on a bad or truncated file.
  void save(const std::string& path) const;
  static BevGrid load(const std::string& path);
  // Frames and traversals from a grid file's header, without reading its tiles (a city's worth of
  // roads: lanemap-coverage). Throws BevError on a file that is not a grid.
  struct Header {
    int frames = 0, traversals = 0;
  };
  static Header readHeader(const std::string& path);

 private:
  using Key = int64_t;
  static Key key(int tx, int ty) { return (static_cast<int64_t>(tx) << 32) ^ static_cast<uint32_t>(ty); }
  Cell tileOrigin(Key k) const;
  BevGridOptions options_;
  int frames_ = 0;
  int traversals_ = 0;  // 0: not counted (see traversals())
  int merges_ = 0;
  double agreement_ = 0.0;
  std::unordered_map<Key, std::vector<uint16_t>> tiles_;
};

}  // namespace lanemap::bev
