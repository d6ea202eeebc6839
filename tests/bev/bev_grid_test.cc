#include "core/bev/bev_grid.h"
#include "tests/common/read_file.h"
#include "tests/common/temp_dir.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace {

using lanemap::bev::BevError;
using lanemap::bev::BevGrid;
using lanemap::bev::Layer;

TEST(BevGrid, CellsFollowTheResolutionOnBothSidesOfTheOrigin) {
  BevGrid g;  // 0.1 m
  EXPECT_EQ(g.cellOf({0.05, 0.05}), BevGrid::Cell(0, 0));
  EXPECT_EQ(g.cellOf({-0.05, 0.15}), BevGrid::Cell(-1, 1));
  EXPECT_EQ(g.cellOf({-12.81, 3.0}), BevGrid::Cell(-129, 30));
  EXPECT_TRUE(g.cellCentre({-1, 1}).isApprox(Eigen::Vector2d(-0.05, 0.15)));
}

TEST(BevGrid, CountsAndFractionsAcrossTiles) {
  BevGrid g;
  const BevGrid::Cell a(-1, -1), b(127, 128), c(128, 128);  // three different tiles
  for (int i = 0; i < 4; ++i) g.add(a, Layer::kObserved);
  g.add(a, Layer::kSolidLine, 3);
  g.add(b, Layer::kObserved);
  g.add(c, Layer::kCurb);
  EXPECT_EQ(g.tileCount(), 3u);
  EXPECT_EQ(g.count(a, Layer::kSolidLine), 3);
  EXPECT_EQ(g.count(a, Layer::kDashedLine), 0);
  EXPECT_FLOAT_EQ(g.fraction(a, Layer::kSolidLine), 0.75f);
  EXPECT_FLOAT_EQ(g.fraction(c, Layer::kCurb), 0.0f) << "never observed";
  EXPECT_EQ(g.count(BevGrid::Cell(5000, 5000), Layer::kObserved), 0);
  EXPECT_EQ(g.tileCount(), 3u) << "reading allocates nothing";
  const auto box = g.cellBounds();
  EXPECT_EQ(box.min(), BevGrid::Cell(-128, -128));
  EXPECT_EQ(box.max(), BevGrid::Cell(256, 256));
}

TEST(BevGrid, CountsSaturate) {
  BevGrid g;
  g.add({0, 0}, Layer::kObserved, 65000);
  g.add({0, 0}, Layer::kObserved, 1000);
  EXPECT_EQ(g.count(BevGrid::Cell(0, 0), Layer::kObserved), 65535);
}

TEST(BevGrid, SavesAndLoadsExactly) {
  BevGrid g(lanemap::bev::BevGridOptions{0.2, 32});
  g.add({-40, 7}, Layer::kObserved, 9);
  g.add({-40, 7}, Layer::kDrivable, 8);
  g.add({100, -3}, Layer::kStopLine, 2);
  g.addFrame();
  g.addFrame();
  const lanemap::testing::TempDir dir("bev-grid");
  const std::string path = dir.str("grid.bin");
  g.save(path);
  const BevGrid h = BevGrid::load(path);
  EXPECT_DOUBLE_EQ(h.resolution(), 0.2);
  EXPECT_EQ(h.options().tile_cells, 32);
  EXPECT_EQ(h.frames(), 2);
  EXPECT_EQ(h.tileCount(), 2u);
  EXPECT_EQ(h.count(BevGrid::Cell(-40, 7), Layer::kDrivable), 8);
  EXPECT_EQ(h.count(BevGrid::Cell(100, -3), Layer::kStopLine), 2);
  EXPECT_EQ(h.count(BevGrid::Cell(100, -3), Layer::kCurb), 0);

  // A truncated file and a foreign file are refused with the path in the message.
  std::filesystem::resize_file(path, std::filesystem::file_size(path) - 10);
  try {
    BevGrid::load(path);
    ADD_FAILURE() << "truncated file loaded";
  } catch (const BevError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
  }
  std::ofstream(path) << "<osm/>";
  EXPECT_THROW(BevGrid::load(path), BevError);
  std::remove(path.c_str());
  EXPECT_THROW(BevGrid::load(path), BevError);
}

// Format 002 carries the traversal count; a file of format 001 (an older store: no count) loads
// with the same counts and frames, as one traversal.
TEST(BevGrid, TraversalsAreSavedAndAnOlderFileIsOneTraversal) {
  BevGrid g(lanemap::bev::BevGridOptions{0.1, 16});
  g.add({3, 4}, Layer::kSolidLine, 5);
  g.addFrame();
  EXPECT_EQ(g.traversals(), 1) << "frames and never merged: one drive";
  EXPECT_EQ(BevGrid().traversals(), 0);
  g.setTraversals(3);
  const lanemap::testing::TempDir dir("bev-grid-v1");
  const std::string path = dir.str("grid.bev");
  g.save(path);
  EXPECT_EQ(BevGrid::load(path).traversals(), 3);
  const auto header = BevGrid::readHeader(path);
  EXPECT_EQ(header.frames, 1);
  EXPECT_EQ(header.traversals, 3);

  // The same grid as format 001 wrote it: magic ...001, no traversal field after the frames.
  std::string bytes = lanemap::testing::readFile(path);
  ASSERT_EQ(bytes.substr(0, 8), "LMBEV002");
  bytes[7] = '1';
  bytes.erase(8 + 8 + 4 + 4 + 4, 4);  // magic, resolution, tile size, layers, frames | traversals
  const std::string old_path = dir.str("old.bev");
  std::ofstream(old_path, std::ios::binary) << bytes;
  const BevGrid old = BevGrid::load(old_path);
  EXPECT_EQ(old.frames(), 1);
  EXPECT_EQ(old.count(BevGrid::Cell(3, 4), Layer::kSolidLine), 5);
  EXPECT_EQ(old.traversals(), 1);
  EXPECT_EQ(BevGrid::readHeader(old_path).traversals, 1);
  std::ofstream(old_path) << "LMBEV003 and more bytes than a header";
  EXPECT_THROW(BevGrid::readHeader(old_path), BevError);
}

TEST(BevGrid, BadOptionsAreRefused) {
  EXPECT_THROW(BevGrid(lanemap::bev::BevGridOptions{0.0, 128}), BevError);
  EXPECT_THROW(BevGrid(lanemap::bev::BevGridOptions{0.1, 4}), BevError);
}

}  // namespace
