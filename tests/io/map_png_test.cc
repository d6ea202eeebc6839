// Tests of the lane map picture (core/io/map_png.h): colours land where the map says (lanes,
// intersection lanes, stop line, background), the scale and size options hold, the footer has
// the scale bar and attribution, the PNG file decodes.
#include "core/io/map_png.h"
#include "tests/common/temp_dir.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <unistd.h>

namespace lanemap::io {
namespace {

using map::LaneletKind;
using map::LaneMap;
using map::LineType;
namespace colours = map_png_colours;

// The file's scratch folder (tests/common/temp_dir.h), made on first use and removed at exit.
const lanemap::testing::TempDir& scratch() {
  static const lanemap::testing::TempDir dir("io-map-png");
  return dir;
}
std::filesystem::path tempDir() { return scratch().path(); }

map::LineString line(int64_t id, LineType type, std::vector<Eigen::Vector3d> pts) {
  map::LineString l;
  l.id = id;
  l.type = type;
  l.points = std::move(pts);
  return l;
}

// A two-way road along x (0..60 m): westbound lane y in [0, 3.5] (left bound the double line),
// eastbound lane y in [-3.5, 0]; the eastbound lane ends at a stop line at x = 60 and continues
// through a 20 m intersection lanelet.
LaneMap twoWayRoad() {
  LaneMap m;
  m.origin_lat = 49.0;
  m.origin_lon = 8.4;
  m.lines.push_back(line(1, LineType::kCurb, {{60, 3.5, 0}, {0, 3.5, 0}}));       // westbound right
  m.lines.push_back(line(2, LineType::kSolidSolid, {{0, 0, 0}, {60, 0, 0}}));     // centre
  m.lines.push_back(line(3, LineType::kDashed, {{0, -3.5, 0}, {60, -3.5, 0}}));   // eastbound right
  m.lines.push_back(line(7, LineType::kCurb, {{0, -7, 0}, {60, -7, 0}}));
  m.lines.push_back(line(4, LineType::kStopLine, {{60, 0, 0}, {60, -3.5, 0}}));
  m.lines.push_back(line(5, LineType::kVirtual, {{60, 0, 0}, {80, 0, 0}}));
  m.lines.push_back(line(6, LineType::kVirtual, {{60, -3.5, 0}, {80, -3.5, 0}}));
  map::Lanelet east;
  east.id = 100;
  east.left_id = 2;
  east.right_id = 3;
  east.centre = {{0, -1.75, 0}, {60, -1.75, 0}};
  east.successors = {102};
  east.stop_line_id = 4;
  map::Lanelet east2 = east;
  east2.id = 103;
  east2.left_id = 3;
  east2.right_id = 7;
  east2.centre = {{0, -5.25, 0}, {60, -5.25, 0}};
  east2.successors = {};
  east2.stop_line_id.reset();
  map::Lanelet west;
  west.id = 101;
  west.left_id = 2;  // runs against the lane (LaneMap wants a reversed copy): still drawn right
  west.right_id = 1;
  west.centre = {{60, 1.75, 0}, {0, 1.75, 0}};
  map::Lanelet through;
  through.id = 102;
  through.kind = LaneletKind::kIntersection;
  through.left_id = 5;
  through.right_id = 6;
  through.centre = {{60, -1.75, 0}, {80, -1.75, 0}};
  m.lanelets = {east, east2, west, through};
  return m;
}

cv::Vec3b at(const cv::Mat& img, const MapImageInfo& info, double x, double y) {
  const cv::Point2d p = info.toPixel({x, y});
  return img.at<cv::Vec3b>(cvRound(p.y), cvRound(p.x));
}

cv::Vec3b bgr(const cv::Scalar& s) {
  return cv::Vec3b(static_cast<uchar>(s[0]), static_cast<uchar>(s[1]), static_cast<uchar>(s[2]));
}

double colourDistance(const cv::Vec3b& a, const cv::Scalar& b) {
  return std::sqrt(std::pow(a[0] - b[0], 2) + std::pow(a[1] - b[1], 2) + std::pow(a[2] - b[2], 2));
}

// Thin lines are anti-aliased, so a pixel on one is a blend of the line's colour and what lies
// under it: require it to be nearer the line colour than the colour underneath.
::testing::AssertionResult showsLine(const cv::Vec3b& pixel, const cv::Scalar& line, const cv::Scalar& under) {
  if (colourDistance(pixel, line) < colourDistance(pixel, under)) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "pixel " << pixel << " is nearer " << under << " than " << line;
}

TEST(MapPng, ColoursLandWhereTheMapSays) {
  MapPngOptions options;
  options.metres_per_pixel = 0.1;
  options.margin_m = 5.0;
  options.background_polylines = {{{-20, 20}, {100, 20}}};  // a skeleton road north of the lanes
  MapImageInfo info;
  const cv::Mat img = renderMapImage(twoWayRoad(), options, &info);
  std::filesystem::create_directories(tempDir());
  cv::imwrite((tempDir() / "two_way.png").string(), img);

  // Extent: x -20..100 (skeleton) and y -7..20, plus 5 m margin, at 0.1 m/px.
  EXPECT_DOUBLE_EQ(info.metres_per_pixel, 0.1);
  EXPECT_NEAR(info.bbox.min().x(), -25.0, 1e-9);
  EXPECT_NEAR(info.bbox.max().y(), 25.0, 1e-9);
  EXPECT_EQ(img.cols, 1300);  // 130 m / 0.1
  EXPECT_EQ(info.map_height_px, 370);  // 37 m / 0.1
  EXPECT_EQ(img.rows, info.map_height_px + info.footer_height_px);

  // Interior points, away from lines (>= 0.5 m = 5 px, more than any line's half width).
  EXPECT_EQ(at(img, info, 20, -1.0), bgr(colours::kRoadLane));     // eastbound lane
  EXPECT_EQ(at(img, info, 20, 2.5), bgr(colours::kRoadLane));      // westbound lane
  EXPECT_EQ(at(img, info, 70, -1.0), bgr(colours::kIntersectionLane));
  EXPECT_EQ(at(img, info, 60, -1.0), bgr(colours::kStopLine));     // on the stop line
  EXPECT_EQ(at(img, info, 30, 20), bgr(colours::kSkeleton));       // skeleton road
  EXPECT_EQ(at(img, info, 30, 10), bgr(colours::kBackground));     // off the road
  EXPECT_EQ(at(img, info, 90, -1.0), bgr(colours::kBackground));
  EXPECT_TRUE(showsLine(at(img, info, 20, -1.75), colours::kCentre, colours::kRoadLane));
  EXPECT_TRUE(showsLine(at(img, info, 20, 0.15), colours::kDoubleSolid, colours::kRoadLane));
  EXPECT_TRUE(showsLine(at(img, info, 20, -0.15), colours::kDoubleSolid, colours::kRoadLane));
  // Two separate lines: between them the lane shows through (nearly: anti-aliased edges).
  EXPECT_TRUE(showsLine(at(img, info, 20, 0.0), colours::kRoadLane, colours::kDoubleSolid));

  // Dashed line: 3 m dash from x = 0, 3 m gap: marking at x = 1.5, lane colour at x = 4.5.
  EXPECT_TRUE(showsLine(at(img, info, 1.5, -3.5), colours::kMarking, colours::kRoadLane));
  EXPECT_EQ(at(img, info, 4.5, -3.5), bgr(colours::kRoadLane));

  // Footer: white band with dark text/scale bar pixels in both halves.
  const cv::Mat footer = img(cv::Rect(0, info.map_height_px + 1, img.cols, info.footer_height_px - 1));
  cv::Mat gray;
  cv::cvtColor(footer, gray, cv::COLOR_BGR2GRAY);
  const int half = img.cols / 2;
  EXPECT_GT(cv::countNonZero(gray(cv::Rect(0, 0, half, gray.rows)) < 100), 100);     // scale bar
  EXPECT_GT(cv::countNonZero(gray(cv::Rect(half, 0, half, gray.rows)) < 150), 100);  // attribution
  EXPECT_GT(cv::countNonZero(gray > 250), gray.total() / 2);
}

TEST(MapPng, MaxImageSizeCoarsensTheScale) {
  MapPngOptions options;
  options.metres_per_pixel = 0.01;
  options.max_image_size = 500;
  options.bbox = Eigen::AlignedBox2d(Eigen::Vector2d(-10, -20), Eigen::Vector2d(90, 30));
  MapImageInfo info;
  const cv::Mat img = renderMapImage(twoWayRoad(), options, &info);
  EXPECT_DOUBLE_EQ(info.metres_per_pixel, 100.0 / 500);
  EXPECT_EQ(img.cols, 500);
  EXPECT_EQ(info.map_height_px, 250);
  EXPECT_EQ(at(img, info, 20, -1.0), bgr(colours::kRoadLane));  // still drawn (5 px wide lane)
}

TEST(MapPng, WritesADecodablePng) {
  std::filesystem::create_directories(tempDir());
  const std::string path = (tempDir() / "map.png").string();
  const MapImageInfo info = writeMapPng(twoWayRoad(), path);
  const cv::Mat back = cv::imread(path);
  ASSERT_FALSE(back.empty());
  EXPECT_EQ(back.rows, info.map_height_px + info.footer_height_px);
  EXPECT_EQ(at(back, info, 20, -1.0), bgr(colours::kRoadLane));
}

TEST(MapPng, EmptyMapAndBadOptions) {
  MapImageInfo info;
  const cv::Mat img = renderMapImage(LaneMap{}, {}, &info);  // 100 m square around the origin
  EXPECT_NEAR(info.bbox.sizes().x(), 120.0, 1e-9);
  EXPECT_FALSE(img.empty());
  MapPngOptions bad;
  bad.metres_per_pixel = 0.0;
  EXPECT_THROW(renderMapImage(twoWayRoad(), bad), IoError);
  const std::string path = (tempDir() / "missing_folder" / "x.png").string();
  try {
    writeMapPng(twoWayRoad(), path);
    FAIL() << "no exception";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lanemap::io
