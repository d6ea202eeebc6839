// Tests of osm::readOsm: counts on the two real files against numbers derived independently with
// the osmium CLI, the tag decisions on small hand-written files, XML vs PBF, and clear OsmErrors
// for missing, empty, malformed and road-less files.
//
// Expected numbers (osmium-tool 1.x, run in data/osm):
//   osmium tags-filter -O -o hw.osm FILE w/highway=motorway,trunk,primary,secondary,tertiary, (continued)
//       unclassified,residential,motorway_link,trunk_link,primary_link,secondary_link, (continued)
//       tertiary_link,living_street,service,road
//   osmium tags-filter -O -i -o drv.osm hw.osm w/service=parking_aisle,driveway w/area=yes w/access=no
//   osmium fileinfo -e drv.osm                -> ways: west-oakland 20, monaco 1673
//   osmium cat -f opl drv.osm -t way | awk '{...N field: distinct node refs...}'
//                                              -> 134 / 15745 distinct nodes
//   monaco has 3 ways with a single node (w156571105, w170077901, w224823020, found with awk on the
//   N field), which readOsm drops with their 3 nodes: 1670 ways, 15742 nodes.
//   osmium tags-filter -R -o - -f opl monaco.osm.pbf r/type=restriction | grep -c '^r'  -> 27,
//   all 27 with a node as via; r3410831 = only_straight_on, from w92627431 via n273244852 to
//   w254596488.
#include "core/osm/coordinate_guard.h"
#include "core/osm/osm_data.h"
#include "tests/common/temp_dir.h"

#include <gtest/gtest.h>
#include <osmium/io/any_input.hpp>
#include <osmium/io/any_output.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace fs = std::filesystem;
using lanemap::osm::OsmData;
using lanemap::osm::OsmError;
using lanemap::osm::readOsm;

namespace {

const std::string kDataDir = LANEMAP_DATA_DIR;

using lanemap::testing::TempDir;

std::string osmXml(const std::string& body) {
  return "<?xml version='1.0' encoding='UTF-8'?>\n<osm version=\"0.6\" generator=\"test\">\n" + body +
         "</osm>\n";
}

// Expects readOsm(path) to throw OsmError whose message contains every one of `parts`.
void expectOsmError(const std::string& path, std::initializer_list<std::string> parts) {
  try {
    readOsm(path);
    FAIL() << "no OsmError for " << path;
  } catch (const OsmError& e) {
    const std::string msg = e.what();
    for (const auto& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
  }
}

const lanemap::osm::Way* findWay(const OsmData& d, int64_t id) {
  auto it = std::find_if(d.ways.begin(), d.ways.end(), [&](const auto& w) { return w.id == id; });
  return it == d.ways.end() ? nullptr : &*it;
}

}  // namespace

TEST(ReadOsm, WestOaklandCountsMatchOsmium) {
  const OsmData d = readOsm(kDataDir + "/osm/west-oakland.osm");
  EXPECT_EQ(d.ways.size(), 20u);
  EXPECT_EQ(d.nodes.size(), 134u);
  EXPECT_TRUE(d.restrictions.empty());
  // Bounds from the file's <bounds> element, exactly.
  EXPECT_DOUBLE_EQ(d.bounds.min_lat, 37.80615);
  EXPECT_DOUBLE_EQ(d.bounds.max_lat, 37.80914);
  EXPECT_DOUBLE_EQ(d.bounds.min_lon, -122.30258);
  EXPECT_DOUBLE_EQ(d.bounds.max_lon, -122.29825);
  EXPECT_TRUE(std::is_sorted(d.ways.begin(), d.ways.end(),
                             [](const auto& a, const auto& b) { return a.id < b.id; }));
  // Goss Street, as osmium prints it: first node n53027353 at lat 37.8073779 lon -122.3006059.
  const auto* goss = findWay(d, 6329561);
  ASSERT_NE(goss, nullptr);
  EXPECT_EQ(goss->tag("name"), "Goss Street");
  EXPECT_EQ(goss->tag("highway"), "residential");
  EXPECT_EQ(goss->tag("lanes", "none"), "none");
  ASSERT_FALSE(goss->nodes.empty());
  EXPECT_EQ(goss->nodes.front(), 53027353);
  EXPECT_NEAR(d.nodes.at(53027353).lat, 37.8073779, 1e-7);  // osmium stores 1e-7 degree fixed point
  EXPECT_NEAR(d.nodes.at(53027353).lon, -122.3006059, 1e-7);
  // Every way node is present.
  for (const auto& w : d.ways) {
    for (int64_t n : w.nodes) EXPECT_TRUE(d.nodes.count(n)) << "way " << w.id << " node " << n;
  }
}

TEST(ReadOsm, MonacoPbfCountsMatchOsmium) {
  const OsmData d = readOsm(kDataDir + "/osm/monaco.osm.pbf");
  EXPECT_EQ(d.ways.size(), 1670u);
  EXPECT_EQ(d.nodes.size(), 15742u);
  EXPECT_EQ(d.restrictions.size(), 27u);
  EXPECT_EQ(findWay(d, 156571105), nullptr);  // single-node way, dropped
  auto it = std::find_if(d.restrictions.begin(), d.restrictions.end(),
                         [](const auto& r) { return r.id == 3410831; });
  ASSERT_NE(it, d.restrictions.end());
  EXPECT_EQ(it->restriction, "only_straight_on");
  EXPECT_EQ(it->from_way, 92627431);
  EXPECT_EQ(it->via_node, 273244852);
  EXPECT_EQ(it->to_way, 254596488);
  EXPECT_DOUBLE_EQ(d.bounds.min_lon, 7.349);
  EXPECT_DOUBLE_EQ(d.bounds.max_lat, 43.77);
}

TEST(ReadOsm, XmlAndPbfGiveTheSameData) {
  TempDir dir("osm-reader");
  const std::string pbf = dir.str("west-oakland.osm.pbf");
  {  // Convert with libosmium's writer (what `osmium cat -o x.pbf` does).
    osmium::io::Reader reader{kDataDir + "/osm/west-oakland.osm"};
    osmium::io::Header header = reader.header();
    osmium::io::Writer writer{pbf, header, osmium::io::overwrite::allow};
    while (osmium::memory::Buffer buffer = reader.read()) writer(std::move(buffer));
    writer.close();
    reader.close();
  }
  const OsmData a = readOsm(kDataDir + "/osm/west-oakland.osm");
  const OsmData b = readOsm(pbf);
  ASSERT_EQ(a.ways.size(), b.ways.size());
  for (size_t i = 0; i < a.ways.size(); ++i) {
    EXPECT_EQ(a.ways[i].id, b.ways[i].id);
    EXPECT_EQ(a.ways[i].nodes, b.ways[i].nodes);
    EXPECT_EQ(a.ways[i].tags, b.ways[i].tags);
  }
  ASSERT_EQ(a.nodes.size(), b.nodes.size());
  for (const auto& [id, n] : a.nodes) {
    EXPECT_DOUBLE_EQ(n.lat, b.nodes.at(id).lat);
    EXPECT_DOUBLE_EQ(n.lon, b.nodes.at(id).lon);
  }
  EXPECT_DOUBLE_EQ(a.bounds.min_lat, b.bounds.min_lat);
}

TEST(ReadOsm, KeepsOnlyDrivableWaysAndTheirNodes) {
  TempDir dir("osm-reader");
  std::string body;
  for (int i = 1; i <= 9; ++i) {
    body += "<node id=\"" + std::to_string(i) + "\" lat=\"43.7" + std::to_string(i) +
            "\" lon=\"7.4" + std::to_string(i) + "\"/>\n";
  }
  auto way = [](int id, const std::string& nds, const std::string& tags) {
    std::string s = "<way id=\"" + std::to_string(id) + "\">";
    for (char c : nds) s += "<nd ref=\"" + std::string(1, c) + "\"/>";
    return s + tags + "</way>\n";
  };
  body += way(10, "12", "<tag k=\"highway\" v=\"residential\"/>");
  body += way(11, "23", "<tag k=\"highway\" v=\"service\"/><tag k=\"service\" v=\"parking_aisle\"/>");
  body += way(12, "34", "<tag k=\"highway\" v=\"service\"/><tag k=\"service\" v=\"driveway\"/>");
  body += way(13, "45", "<tag k=\"highway\" v=\"service\"/><tag k=\"service\" v=\"alley\"/>");
  body += way(14, "56", "<tag k=\"highway\" v=\"footway\"/>");
  body += way(15, "67", "<tag k=\"highway\" v=\"track\"/>");
  body += way(16, "78", "<tag k=\"highway\" v=\"cycleway\"/>");
  body += way(17, "89", "<tag k=\"building\" v=\"yes\"/>");
  // Way 18 references node 99 which is not in the file: the reference is dropped.
  body += "<way id=\"18\"><nd ref=\"1\"/><nd ref=\"99\"/><nd ref=\"9\"/><tag k=\"highway\" v=\"primary_link\"/></way>\n";
  // Way 19 keeps a single present node: dropped.
  body += "<way id=\"19\"><nd ref=\"2\"/><nd ref=\"98\"/><tag k=\"highway\" v=\"primary\"/></way>\n";
  body += "<relation id=\"30\"><member type=\"way\" ref=\"10\" role=\"from\"/><member type=\"node\" ref=\"1\" "
          "role=\"via\"/><member type=\"way\" ref=\"18\" role=\"to\"/><tag k=\"type\" v=\"restriction\"/>"
          "<tag k=\"restriction\" v=\"no_left_turn\"/></relation>\n";
  const OsmData d = readOsm(dir.write("small.osm", osmXml(body)));
  std::vector<int64_t> ids;
  for (const auto& w : d.ways) ids.push_back(w.id);
  EXPECT_EQ(ids, (std::vector<int64_t>{10, 13, 18}));
  EXPECT_EQ(findWay(d, 18)->nodes, (std::vector<int64_t>{1, 9}));
  EXPECT_EQ(d.nodes.size(), 5u);  // 1, 2, 4, 5, 9
  EXPECT_FALSE(d.nodes.count(3));
  ASSERT_EQ(d.restrictions.size(), 1u);
  EXPECT_EQ(d.restrictions[0].restriction, "no_left_turn");
  EXPECT_EQ(d.restrictions[0].via_node, 1);
  // No <bounds>: from the nodes used.
  EXPECT_DOUBLE_EQ(d.bounds.min_lat, 43.71);
  EXPECT_DOUBLE_EQ(d.bounds.max_lat, 43.79);
  EXPECT_TRUE(lanemap::osm::isDrivableHighway("motorway_link"));
  EXPECT_FALSE(lanemap::osm::isDrivableHighway("steps"));
}

TEST(ReadOsm, MissingFileThrowsWithPath) {
  TempDir dir("osm-reader");
  expectOsmError(dir.str("nope.osm"), {"not found", "nope.osm"});
}

TEST(ReadOsm, EmptyFileThrowsWithPath) {
  TempDir dir("osm-reader");
  expectOsmError(dir.write("empty.osm", ""), {"empty", "empty.osm"});
}

TEST(ReadOsm, MalformedXmlThrowsWithPath) {
  TempDir dir("osm-reader");
  expectOsmError(dir.write("broken.osm", "<?xml version='1.0'?>\n<osm version=\"0.6\"><node id=\"1\" lat="),
                 {"broken.osm"});
}

TEST(ReadOsm, GarbagePbfThrowsWithPath) {
  TempDir dir("osm-reader");
  expectOsmError(dir.write("garbage.osm.pbf", std::string(3000, '\x7f')), {"garbage.osm.pbf"});
}

TEST(ReadOsm, UnknownFormatThrowsWithPath) {
  TempDir dir("osm-reader");
  expectOsmError(dir.write("map.txt", "hello"), {"map.txt"});
}

// A coordinate in exponent notation is refused before libosmium parses it (its parser overflows
// a signed integer on a large exponent); "e" elsewhere (a tag's value, another attribute) is not.
TEST(ReadOsm, ACoordinateInExponentNotationIsRefusedBeforeLibosmiumReadsIt) {
  TempDir dir("osm-reader");
  const std::string road =
      "<way id=\"5\"><nd ref=\"1\"/><nd ref=\"2\"/><tag k=\"highway\" v=\"residential\"/>"
      "<tag k=\"note\" v=\"lat='1e5' here\"/></way>\n";
  const std::string good = "<node id=\"1\" lat=\"43.7\" lon=\"7.4\" user=\"lee\"/><node id=\"2\" lat=\"43.71\" lon=\"7.41\"/>\n";
  EXPECT_EQ(readOsm(dir.write("plain.osm", osmXml(good + road))).ways.size(), 1u);
  const std::string bad = "<node id=\"1\" lat=\"43.7\" lon=\"7.4e99999\"/><node id=\"2\" lat=\"43.71\" lon=\"7.41\"/>\n";
  expectOsmError(dir.write("exponent.osm", osmXml(bad + road)), {"exponent notation", "lon=\"7.4e99999\"", "exponent.osm"});
}

// The guard reads large files in 1 MiB blocks: a coordinate whose attribute name and value are cut
// by a block's end is still found, and a file of a few MiB with none passes.
TEST(ReadOsm, AnExponentCoordinateAcrossTheGuardsReadBlocksIsFound) {
  TempDir dir("osm-reader");
  constexpr size_t kBlock = 1 << 20;
  std::string filler;
  for (int i = 10; filler.size() < 3 * kBlock; ++i) {
    filler += "<node id=\"" + std::to_string(i) + "\" lat=\"43.7\" lon=\"7.4\"/>\n";
  }
  const std::string head = "<?xml version=\"1.0\"?>\n<osm version=\"0.6\">\n";
  const std::string clean = head + filler + "</osm>\n";
  EXPECT_EQ(lanemap::osm::exponentCoordinate(dir.write("clean.osm", clean)), "");
  for (const size_t cut : {2u, 5u, 9u}) {  // the block ends inside `lon`, at its '"', inside its value
    const std::string bad = "<node id=\"2\" lon=\"7.4e5\" lat=\"43.7\"/>\n";
    std::string text = head + filler.substr(0, filler.rfind('\n', kBlock - head.size() - 100) + 1);
    // Blanks, so that "lon" starts `cut` bytes before the first block's end.
    const size_t before_lon = std::string("<node id=\"2\" ").size();
    text.append(kBlock - text.size() - before_lon - cut, ' ');
    text += bad + filler.substr(0, kBlock) + "</osm>\n";
    ASSERT_EQ(text.compare(kBlock - cut, 3, std::string("lon=\"7.4e5\"").substr(0, 3)), 0) << cut;
    EXPECT_EQ(lanemap::osm::exponentCoordinate(dir.write("cut" + std::to_string(cut) + ".osm", text)), "lon=\"7.4e5\"") << cut;
  }
}

TEST(ReadOsm, NoDrivableWayThrows) {
  TempDir dir("osm-reader");
  const std::string body =
      "<node id=\"1\" lat=\"43.7\" lon=\"7.4\"/><node id=\"2\" lat=\"43.71\" lon=\"7.41\"/>\n"
      "<way id=\"5\"><nd ref=\"1\"/><nd ref=\"2\"/><tag k=\"highway\" v=\"footway\"/></way>\n";
  expectOsmError(dir.write("paths.osm", osmXml(body)), {"no drivable", "paths.osm"});
}
