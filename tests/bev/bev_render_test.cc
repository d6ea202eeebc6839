// lanemap-render's picture (core/bev/bev_render.h): north up, one pixel per cell, each layer in its
// colour where it holds a share of the observations, the skeleton drawn over it; the tool writes it.
#include "core/bev/bev_grid.h"
#include "core/bev/bev_render.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

namespace {

using lanemap::bev::BevGrid;
using lanemap::bev::Layer;

BevGrid sample() {
  BevGrid g(lanemap::bev::BevGridOptions{0.1, 16});
  for (int x = 0; x < 20; ++x) g.add({x, 3}, Layer::kObserved, 4);
  g.add({2, 3}, Layer::kDrivable, 4);
  g.add({5, 3}, Layer::kSolidLine, 2);   // half of the looks
  g.add({6, 3}, Layer::kCrosswalk, 1);   // a quarter: below the 0.3 share
  g.add({-3, 20}, Layer::kObserved, 1);  // a second tile, north-west
  g.add({-3, 20}, Layer::kCurb, 1);
  return g;
}

TEST(BevRender, LayersGetTheirColoursNorthUp) {
  const BevGrid g = sample();
  const cv::Mat img = lanemap::bev::renderBev(g);
  // Tiles of 16 cells: x in [-16, 32), y in [0, 32).
  ASSERT_EQ(img.cols, 48);
  ASSERT_EQ(img.rows, 32);
  auto at = [&](int x, int y) { return img.at<cv::Vec3b>(31 - y, x + 16); };
  EXPECT_EQ(at(2, 3), lanemap::bev::layerColour(Layer::kDrivable));
  EXPECT_EQ(at(5, 3), lanemap::bev::layerColour(Layer::kSolidLine));
  EXPECT_EQ(at(6, 3), lanemap::bev::layerColour(Layer::kObserved));
  EXPECT_EQ(at(-3, 20), lanemap::bev::layerColour(Layer::kCurb));
  EXPECT_EQ(at(10, 10), cv::Vec3b(0, 0, 0)) << "never observed";
  const cv::Point2d p = lanemap::bev::bevPixel(g, Eigen::Vector2d(0.25, 0.35));
  EXPECT_NEAR(p.x, 18.5, 1e-9);
  EXPECT_NEAR(p.y, 28.5, 1e-9);
  // A polyline along y = 1.05 m (row 10) is drawn in green across.
  const cv::Mat with = lanemap::bev::renderBev(g, {{Eigen::Vector2d(-1.0, 1.05), Eigen::Vector2d(2.0, 1.05)}});
  const cv::Vec3b c = with.at<cv::Vec3b>(31 - 10, 16 + 5);
  EXPECT_GT(c[1], 100);
  EXPECT_LT(c[0], 50);
}

TEST(BevRender, TheToolWritesThePng) {
  lanemap::testing::TempDir dir("bev-render");
  sample().save(dir.str("g.bev"));
  const auto r = lanemap::testing::runCommand(lanemap::testing::binPath("lanemap-render") + " --bev " + dir.str("g.bev") +
                                              " --png " + dir.str("g.png") + " --scale 3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const cv::Mat img = cv::imread(dir.str("g.png"));
  EXPECT_EQ(img.cols, 48 * 3);
  EXPECT_EQ(img.rows, 32 * 3);
  EXPECT_EQ(img.at<cv::Vec3b>(3 * (31 - 3) + 1, 3 * (16 + 2) + 1), lanemap::bev::layerColour(Layer::kDrivable));
  const auto bad = lanemap::testing::runCommand(lanemap::testing::binPath("lanemap-render") + " --bev " +
                                                lanemap::testing::dataPath("osm/west-oakland.osm") + " --png " + dir.str("x.png"));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("bad magic"), std::string::npos) << bad.output;
}

TEST(BevRender, PictureIsShrunkToItsLongestSideKeepingThinLinesAndPlacedByItsCells) {
  // A 100 m x 2 m strip of drivable cells along x with a one-cell solid line along its middle, and
  // one background-only cell.
  BevGrid g(lanemap::bev::BevGridOptions{0.1, 64});
  for (int x = 0; x < 1000; ++x) {
    for (int y = 0; y < 20; ++y) {
      g.add({x, y}, Layer::kObserved, 4);
      g.add({x, y}, y == 10 ? Layer::kSolidLine : Layer::kDrivable, 4);
    }
  }
  g.add({0, 40}, Layer::kObserved, 2);
  EXPECT_THROW(lanemap::bev::bevPicture(BevGrid(), 100), lanemap::bev::BevError);
  EXPECT_THROW(lanemap::bev::bevPicture(g, 0), lanemap::bev::BevError);
  const auto pic = lanemap::bev::bevPicture(g, 100);
  // Allocated: 16 x 1 tiles of 64 cells = 1024 x 64 cells; 100 px at most: stride 11.
  EXPECT_EQ(pic.stride, 11);
  EXPECT_EQ(pic.width, 94);  // ceil(1024 / 11)
  EXPECT_EQ(pic.height, 6);  // ceil(64 / 11)
  EXPECT_NEAR(pic.enu.min().x(), 0.0, 1e-9);
  EXPECT_NEAR(pic.enu.min().y(), 0.0, 1e-9);
  EXPECT_NEAR(pic.enu.max().x(), 94 * 1.1, 1e-9);
  EXPECT_NEAR(pic.enu.max().y(), 6 * 1.1, 1e-9);
  const cv::Mat img = cv::imdecode(pic.png, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(img.type(), CV_8UC4);
  ASSERT_EQ(img.cols, pic.width);
  ASSERT_EQ(img.rows, pic.height);
  // Rows from the south: cells y 0..10 are row 5 (the bottom one) and hold the solid line (y = 10),
  // which wins over the drivable cells around it; y 11..21 (row 4) only drivable.
  const auto bgra = [&](int row, int col) { return img.at<cv::Vec4b>(row, col); };
  const cv::Vec3b solid = lanemap::bev::layerColour(Layer::kSolidLine), drivable = lanemap::bev::layerColour(Layer::kDrivable);
  for (int c : {0, 40, 90}) {
    EXPECT_EQ(cv::Vec3b(bgra(5, c)[0], bgra(5, c)[1], bgra(5, c)[2]), solid) << c;
    EXPECT_EQ(bgra(5, c)[3], 255);
    EXPECT_EQ(cv::Vec3b(bgra(4, c)[0], bgra(4, c)[1], bgra(4, c)[2]), drivable) << c;
  }
  EXPECT_EQ(bgra(2, 0)[3], lanemap::bev::kPictureBackgroundAlpha);  // cell (0, 40): seen, background only
  EXPECT_EQ(bgra(2, 10)[3], 0);                                     // never seen: transparent
  EXPECT_EQ(bgra(0, 50)[3], 0);
  // A picture that fits is one pixel per cell.
  EXPECT_EQ(lanemap::bev::bevPicture(g, 1024).stride, 1);
}

}  // namespace
