#include "core/bev/bev_grid.h"

#include "core/io/atomic_file.h"
#include "core/io/read_file.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>

namespace lanemap::bev {

Eigen::Vector2i CellMove::apply(const Eigen::Vector2i& cell, const Eigen::Vector2d& shears) const {
  if (rotation_rad == 0.0) return cell + shift;
  const auto round = [](double v) { return static_cast<int>(std::lround(v)); };
  int x = cell.x() - pivot.x(), y = cell.y() - pivot.y();
  x += round(shears.x() * y);
  y += round(shears.y() * x);
  x += round(shears.x() * y);
  return Eigen::Vector2i(x + pivot.x() + shift.x(), y + pivot.y() + shift.y());
}

namespace {

constexpr char kMagic[8] = {'L', 'M', 'B', 'E', 'V', '0', '0', '3'};
constexpr char kMagicV2[8] = {'L', 'M', 'B', 'E', 'V', '0', '0', '2'};  // no merges, agreement
constexpr char kMagicV1[8] = {'L', 'M', 'B', 'E', 'V', '0', '0', '1'};  // no traversals

// The format of a grid file from its first bytes: 1, 2 or 3 (kMagicV1, kMagicV2, kMagic); throws
// BevError for anything else.
int formatOf(const std::string& in, const std::string& path) {
  const auto is = [&](const char (&magic)[8]) {
    return in.size() >= sizeof(magic) && std::memcmp(in.data(), magic, sizeof(magic)) == 0;
  };
  if (is(kMagicV1)) return 1;
  if (is(kMagicV2)) return 2;
  if (is(kMagic)) return 3;
  throw BevError("not a lanemap BEV grid file (bad magic): " + path);
}

int floorDiv(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

template <typename T>
void put(std::string& out, T v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

template <typename T>
T get(const std::string& in, size_t& pos, const std::string& path) {
  if (pos + sizeof(T) > in.size()) throw BevError("BEV grid file truncated: " + path);
  T v;
  std::memcpy(&v, in.data() + pos, sizeof(T));
  pos += sizeof(T);
  return v;
}

}  // namespace

const char* toString(Layer layer) {
  switch (layer) {
    case Layer::kObserved: return "observed";
    case Layer::kDrivable: return "drivable";
    case Layer::kLaneSeparation: return "lane_separation";
    case Layer::kDashedLine: return "dashed_line";
    case Layer::kSolidLine: return "solid_line";
    case Layer::kCrosswalk: return "crosswalk";
    case Layer::kCurb: return "curb";
    case Layer::kStopLine: return "stop_line";
    case Layer::kCount: break;
  }
  return "?";
}

BevGrid::BevGrid(BevGridOptions options) : options_(options) {
  if (!(options_.resolution_m > 0.0) || !std::isfinite(options_.resolution_m)) {
    throw BevError("BEV grid resolution must be > 0 m");
  }
  if (options_.tile_cells < 8 || options_.tile_cells > 1024) throw BevError("BEV grid tile_cells must be in [8, 1024]");
}

BevGrid::Cell BevGrid::cellOf(const Eigen::Vector2d& enu) const {
  return Cell(static_cast<int>(std::floor(enu.x() / options_.resolution_m)),
              static_cast<int>(std::floor(enu.y() / options_.resolution_m)));
}

Eigen::Vector2d BevGrid::cellCentre(const Cell& c) const {
  return Eigen::Vector2d((c.x() + 0.5) * options_.resolution_m, (c.y() + 0.5) * options_.resolution_m);
}

BevGrid::Cell BevGrid::tileOrigin(Key k) const {
  const int tx = static_cast<int>(k >> 32);
  const int ty = static_cast<int>(static_cast<int32_t>(k & 0xffffffff));
  return Cell(tx * options_.tile_cells, ty * options_.tile_cells);
}

void BevGrid::add(const Cell& cell, Layer layer, uint16_t n) {
  const int t = options_.tile_cells;
  const int tx = floorDiv(cell.x(), t), ty = floorDiv(cell.y(), t);
  auto& tile = tiles_[key(tx, ty)];
  if (tile.empty()) tile.assign(static_cast<size_t>(kNumLayers) * t * t, 0);
  const size_t idx = static_cast<size_t>(layer) * t * t + static_cast<size_t>(cell.y() - ty * t) * t + (cell.x() - tx * t);
  const uint32_t v = static_cast<uint32_t>(tile[idx]) + n;
  tile[idx] = static_cast<uint16_t>(std::min<uint32_t>(v, std::numeric_limits<uint16_t>::max()));
}

uint16_t BevGrid::count(const Cell& cell, Layer layer) const {
  const int t = options_.tile_cells;
  const int tx = floorDiv(cell.x(), t), ty = floorDiv(cell.y(), t);
  const auto it = tiles_.find(key(tx, ty));
  if (it == tiles_.end()) return 0;
  return it->second[static_cast<size_t>(layer) * t * t + static_cast<size_t>(cell.y() - ty * t) * t + (cell.x() - tx * t)];
}

float BevGrid::fraction(const Cell& cell, Layer layer) const {
  const uint16_t seen = count(cell, Layer::kObserved);
  return seen == 0 ? 0.0f : static_cast<float>(count(cell, layer)) / static_cast<float>(seen);
}

Eigen::AlignedBox2i BevGrid::cellBounds() const {
  Eigen::AlignedBox2i box;  // empty
  for (const auto& [k, tile] : tiles_) {
    const Cell o = tileOrigin(k);
    box.extend(o);
    box.extend(Cell(o.x() + options_.tile_cells, o.y() + options_.tile_cells));
  }
  return box;
}

size_t BevGrid::memoryBytes() const {
  return tiles_.size() * (static_cast<size_t>(kNumLayers) * options_.tile_cells * options_.tile_cells * sizeof(uint16_t) + 64);
}

void BevGrid::save(const std::string& path) const {
  std::string out;
  const size_t tile_bytes = static_cast<size_t>(kNumLayers) * options_.tile_cells * options_.tile_cells * sizeof(uint16_t);
  out.reserve(sizeof(kMagic) + 64 + tiles_.size() * (sizeof(int64_t) + tile_bytes));  // one allocation: grids run to megabytes
  out.append(kMagic, sizeof(kMagic));
  put<double>(out, options_.resolution_m);
  put<int32_t>(out, options_.tile_cells);
  put<int32_t>(out, kNumLayers);
  put<int32_t>(out, frames_);
  put<int32_t>(out, traversals());
  put<int32_t>(out, merges_);
  put<double>(out, agreement_);
  put<uint64_t>(out, tiles_.size());
  // Sorted by key so the same grid always gives the same bytes.
  std::vector<Key> keys;
  for (const auto& [k, tile] : tiles_) keys.push_back(k);
  std::sort(keys.begin(), keys.end());
  for (Key k : keys) {
    put<int64_t>(out, k);
    const auto& tile = tiles_.at(k);
    out.append(reinterpret_cast<const char*>(tile.data()), tile.size() * sizeof(uint16_t));
  }
  io::writeFileAtomically(path, out);
}

BevGrid BevGrid::load(const std::string& path) {
  const std::optional<std::string> content = io::readFile(path);
  if (!content) throw BevError("cannot read BEV grid file: " + path);
  const std::string& in = *content;
  const int format = formatOf(in, path);
  size_t pos = sizeof(kMagic);
  BevGridOptions opt;
  opt.resolution_m = get<double>(in, pos, path);
  opt.tile_cells = get<int32_t>(in, pos, path);
  const int32_t layers = get<int32_t>(in, pos, path);
  if (layers != kNumLayers) throw BevError("BEV grid file has " + std::to_string(layers) + " layers, expected " + std::to_string(kNumLayers) + ": " + path);
  BevGrid grid(opt);  // validates resolution and tile size
  grid.frames_ = get<int32_t>(in, pos, path);
  if (format >= 2) {
    grid.traversals_ = get<int32_t>(in, pos, path);
    if (grid.traversals_ < 0) throw BevError("BEV grid file has a negative traversal count: " + path);
  }
  if (format >= 3) {
    grid.merges_ = get<int32_t>(in, pos, path);
    grid.agreement_ = get<double>(in, pos, path);
    if (grid.merges_ < 0 || !(grid.agreement_ >= 0.0 && grid.agreement_ <= grid.merges_))
      throw BevError("BEV grid file has a bad merge count or agreement: " + path);
  }
  const uint64_t n = get<uint64_t>(in, pos, path);
  const size_t tile_bytes = static_cast<size_t>(kNumLayers) * opt.tile_cells * opt.tile_cells * sizeof(uint16_t);
  if (n > (in.size() - pos) / (tile_bytes + sizeof(int64_t))) throw BevError("BEV grid file truncated: " + path);
  for (uint64_t i = 0; i < n; ++i) {
    const Key k = get<int64_t>(in, pos, path);
    auto& tile = grid.tiles_[k];
    tile.resize(tile_bytes / sizeof(uint16_t));
    std::memcpy(tile.data(), in.data() + pos, tile_bytes);
    pos += tile_bytes;
  }
  if (pos != in.size()) throw BevError("BEV grid file has trailing bytes: " + path);
  return grid;
}

void BevGrid::addMerge(double agreement) { addMerges(1, std::clamp(agreement, 0.0, 1.0)); }

void BevGrid::addMerges(int merges, double agreement) {
  merges_ += merges;
  agreement_ += agreement;
}

BevGrid::Header BevGrid::readHeader(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw BevError("cannot read BEV grid file: " + path);
  std::string in(8 + 8 + 4 + 4 + 4 + 4, '\0');
  f.read(in.data(), static_cast<std::streamsize>(in.size()));
  in.resize(static_cast<size_t>(f.gcount()));
  const int format = formatOf(in, path);
  size_t pos = sizeof(kMagic) + 8 + 4 + 4;  // resolution, tile size, layers
  BevGrid g;
  g.frames_ = get<int32_t>(in, pos, path);
  if (format >= 2) g.traversals_ = std::max(0, get<int32_t>(in, pos, path));
  return {g.frames(), g.traversals()};
}

}  // namespace lanemap::bev
