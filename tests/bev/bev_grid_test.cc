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

// Format 003 carries the traversal count, merges and agreement; files of format 002 (no merges)
// and 001 (an older store: no count) load with the same counts and frames: 002 with no merge, 001
// as one traversal.
TEST(BevGrid, TraversalsAndAgreementAreSavedAndAnOlderFileLoads) {
  BevGrid g(lanemap::bev::BevGridOptions{0.1, 16});
  g.add({3, 4}, Layer::kSolidLine, 5);
  g.addFrame();
  EXPECT_EQ(g.traversals(), 1) << "frames and never merged: one drive";
  EXPECT_EQ(BevGrid().traversals(), 0);
  g.setTraversals(3);
  g.addMerge(0.75);
  g.addMerge(1.7);   // clipped to 1
  g.addMerge(-0.2);  // clipped to 0
  EXPECT_EQ(g.merges(), 3);
  EXPECT_DOUBLE_EQ(g.agreement(), 1.75);
  const lanemap::testing::TempDir dir("bev-grid-v1");
  const std::string path = dir.str("grid.bev");
  g.save(path);
  const BevGrid loaded = BevGrid::load(path);
  EXPECT_EQ(loaded.traversals(), 3);
  EXPECT_EQ(loaded.merges(), 3);
  EXPECT_DOUBLE_EQ(loaded.agreement(), 1.75);
  const auto header = BevGrid::readHeader(path);
  EXPECT_EQ(header.frames, 1);
  EXPECT_EQ(header.traversals, 3);

  // The same grid as format 002 wrote it: magic ...002, no merges and agreement after traversals.
  std::string bytes = lanemap::testing::readFile(path);
  ASSERT_EQ(bytes.substr(0, 8), "LMBEV003");
  const size_t after_traversals = 8 + 8 + 4 + 4 + 4 + 4;  // magic, resolution, tile size, layers, frames, traversals
  std::string v2 = bytes;
  v2[7] = '2';
  v2.erase(after_traversals, 4 + 8);
  const std::string v2_path = dir.str("v2.bev");
  std::ofstream(v2_path, std::ios::binary) << v2;
  const BevGrid older = BevGrid::load(v2_path);
  EXPECT_EQ(older.traversals(), 3);
  EXPECT_EQ(older.merges(), 0);
  EXPECT_EQ(older.agreement(), 0.0);
  EXPECT_EQ(older.count(BevGrid::Cell(3, 4), Layer::kSolidLine), 5);
  EXPECT_EQ(BevGrid::readHeader(v2_path).traversals, 3);

  // Format 001: no traversal field after the frames either.
  std::string v1 = v2;
  v1[7] = '1';
  v1.erase(after_traversals - 4, 4);
  const std::string old_path = dir.str("old.bev");
  std::ofstream(old_path, std::ios::binary) << v1;
  const BevGrid old = BevGrid::load(old_path);
  EXPECT_EQ(old.frames(), 1);
  EXPECT_EQ(old.count(BevGrid::Cell(3, 4), Layer::kSolidLine), 5);
  EXPECT_EQ(old.traversals(), 1);
  EXPECT_EQ(BevGrid::readHeader(old_path).traversals, 1);

  // A bad agreement (more than one per merge) is refused; so is a format from the future.
  std::string bad = bytes;
  const double too_much = 9.0;
  bad.replace(after_traversals + 4, 8, reinterpret_cast<const char*>(&too_much), 8);
  const std::string bad_path = dir.str("bad.bev");
  std::ofstream(bad_path, std::ios::binary) << bad;
  EXPECT_THROW(BevGrid::load(bad_path), BevError);
  std::ofstream(old_path) << "LMBEV004 and more bytes than a header";
  EXPECT_THROW(BevGrid::readHeader(old_path), BevError);
}

TEST(BevGrid, BadOptionsAreRefused) {
  EXPECT_THROW(BevGrid(lanemap::bev::BevGridOptions{0.0, 128}), BevError);
  EXPECT_THROW(BevGrid(lanemap::bev::BevGridOptions{0.1, 4}), BevError);
}

}  // namespace
