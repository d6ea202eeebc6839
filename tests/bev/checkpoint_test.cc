// Checkpoints of open roads (core/bev/bev_store.h) and restoring them into the accumulator
// (RoadBevAccumulator::restore, BevBuilder::restoreRoad): what a BEV builder that restarts
// mid-road carries on from.
#include "core/bev/bev_builder.h"
#include "core/bev/bev_store.h"
#include "core/bev/checkpoint_writer.h"
#include "core/bev/road_bev.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <future>

namespace {

using namespace lanemap;
namespace lt = lanemap::testing;

bev::RoadBev roadWithEvidence(const skeleton::Skeleton& sk, int64_t road_id, int frames) {
  bev::RoadBevAccumulator acc(sk);
  EXPECT_TRUE(acc.open(road_id, 1000));
  bev::RoadBev r = *acc.close(road_id, 2000);
  for (int i = 0; i < 30; ++i) {
    r.grid.add({i, 7}, bev::Layer::kObserved, 3);
    r.grid.add({i, 7}, bev::Layer::kDrivable, 2);
  }
  for (int f = 0; f < frames; ++f) r.grid.addFrame();
  return r;
}

TEST(Checkpoint, StoredLoadedAndRemovedWithTheNewestFrameTime) {
  const auto sk = skeleton::Skeleton::build(osm::readOsm(std::string(LANEMAP_DATA_DIR) + "/osm/west-oakland.osm"));
  lt::TempDir store("checkpoint");
  EXPECT_TRUE(bev::loadCheckpoints(store.str()).empty());  // no bev/open/ folder: nothing
  const int64_t a = sk.roads()[0].id, b = sk.roads()[1].id;
  bev::storeCheckpoint(store.str(), roadWithEvidence(sk, a, 12), 1'700'000'000'500'000);
  bev::storeCheckpoint(store.str(), roadWithEvidence(sk, b, 3), 0);
  EXPECT_EQ(bev::checkpointPath(store.str(), a), store.str("bev/open/road_" + std::to_string(a) + ".bev"));
  // A newer checkpoint of a road replaces the older one.
  bev::storeCheckpoint(store.str(), roadWithEvidence(sk, a, 20), 1'700'000'001'000'000);
  auto loaded = bev::loadCheckpoints(store.str());
  ASSERT_EQ(loaded.size(), 2u);
  const auto& ca = loaded[0].road_id == a ? loaded[0] : loaded[1];
  EXPECT_EQ(ca.road_id, a);
  EXPECT_EQ(ca.grid.frames(), 20);
  EXPECT_EQ(ca.last_frame_utime, 1'700'000'001'000'000);
  EXPECT_EQ(ca.grid.count(bev::BevGrid::Cell(5, 7), bev::Layer::kDrivable), 2);
  // An unreadable checkpoint is named, the others still load.
  { std::ofstream(store.str("bev/open/road_999.bev")) << "not a grid"; }
  std::vector<std::string> errors;
  loaded = bev::loadCheckpoints(store.str(), &errors);
  EXPECT_EQ(loaded.size(), 2u);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("road_999.bev"), std::string::npos) << errors[0];
  // The store's file listing: road_<id>.bev only (not a half-written temporary, not other names).
  { std::ofstream(store.str("bev/open/road_7.bev.tmp.42")) << "x"; }
  { std::ofstream(store.str("bev/open/road_x.bev")) << "x"; }
  { std::ofstream(store.str("bev/open/road_-3.bev")) << "x"; }
  const auto listed = bev::roadFiles(store.str("bev/open"), ".bev");
  EXPECT_EQ(listed.size(), 4u);  // a, b, 999, -3
  EXPECT_TRUE(listed.count(-3));
  EXPECT_FALSE(listed.count(7));
  EXPECT_EQ(listed.at(a), bev::checkpointPath(store.str(), a));
  EXPECT_TRUE(bev::roadFiles(store.str("no-such-folder"), ".bev").empty());
  std::filesystem::remove(store.str("bev/open/road_-3.bev"));
  bev::removeCheckpoint(store.str(), a);
  bev::removeCheckpoint(store.str(), 999);
  bev::removeCheckpoint(store.str(), 12345);  // none: nothing happens
  loaded = bev::loadCheckpoints(store.str());
  ASSERT_EQ(loaded.size(), 1u);
  EXPECT_EQ(loaded[0].road_id, b);
  EXPECT_FALSE(std::filesystem::exists(store.str("bev/open/road_" + std::to_string(a) + ".json")));
}

TEST(Checkpoint, ARestoredRoadIsActiveAgainAndGoesOnCollecting) {
  const auto sk = skeleton::Skeleton::build(osm::readOsm(std::string(LANEMAP_DATA_DIR) + "/osm/west-oakland.osm"));
  const int64_t a = sk.roads()[0].id;
  bev::RoadBevAccumulator acc(sk);
  bev::RoadBev saved = roadWithEvidence(sk, a, 12);
  EXPECT_FALSE(acc.restore(-77, saved.grid, 0));  // unknown road
  EXPECT_FALSE(acc.restore(a, bev::BevGrid(bev::BevGridOptions{0.2, 128}), 0));  // another resolution
  ASSERT_TRUE(acc.restore(a, saved.grid, 5000));
  EXPECT_FALSE(acc.restore(a, saved.grid, 5000));  // already active
  ASSERT_NE(acc.active(a), nullptr);
  EXPECT_EQ(acc.active(a)->grid.frames(), 12);
  EXPECT_EQ(acc.active(a)->from_node, sk.road(a)->from);
  // Closing hands over the restored evidence.
  const auto closed = acc.close(a, 9000);
  ASSERT_TRUE(closed);
  EXPECT_EQ(closed->grid.count(bev::BevGrid::Cell(3, 7), bev::Layer::kObserved), 3);
  EXPECT_EQ(closed->opened_utime, 5000);
}

}  // namespace

// The BEV builder's checkpoints are written in a thread of their own (issue 17: frames waited
// behind each fsync). What the store's crash rules need of it: the caller never waits for a write,
// the newest asked content lands, and after cancel(road) no older checkpoint of that road lands
// (it would make a stored road look open to the next start).
TEST(CheckpointWriter, WritesInItsOwnThreadAndCancelIsABarrier) {
  const auto sk = skeleton::Skeleton::build(osm::readOsm(std::string(LANEMAP_DATA_DIR) + "/osm/west-oakland.osm"));
  lt::TempDir store("checkpoint_writer");
  const int64_t a = sk.roads()[0].id, b = sk.roads()[1].id;
  std::promise<void> entered, release;
  std::shared_future<void> released = release.get_future().share();
  bool first = true;
  auto writer = std::make_unique<bev::CheckpointWriter>(store.str());
  writer->setBeforeWriteHook([&](int64_t) {
    if (!first) return;
    first = false;
    entered.set_value();
    released.wait();  // the first write blocks, as a slow disk would
  });
  writer->write(roadWithEvidence(sk, a, 5), 5);
  entered.get_future().wait();  // the writer is inside road a's first write
  // The caller goes on while the writer is stuck: these return at once (a deadlock otherwise).
  auto asked = std::async(std::launch::async, [&] {
    writer->write(roadWithEvidence(sk, a, 6), 6);
    writer->write(roadWithEvidence(sk, b, 3), 3);
    writer->write(roadWithEvidence(sk, a, 7), 7);  // replaces the waiting write of a (6 frames)
    writer->write(roadWithEvidence(sk, b, 4), 4);  // and of b
  });
  ASSERT_EQ(asked.wait_for(std::chrono::seconds(20)), std::future_status::ready);
  EXPECT_EQ(writer->stats().written, 0);
  EXPECT_EQ(writer->stats().replaced, 2);
  // cancel(a) drops a's waiting write and waits for the one in progress: it cannot return before
  // the write is released.
  auto cancelled = std::async(std::launch::async, [&] { writer->cancel(a); });
  EXPECT_EQ(cancelled.wait_for(std::chrono::milliseconds(200)), std::future_status::timeout);
  release.set_value();
  ASSERT_EQ(cancelled.wait_for(std::chrono::seconds(20)), std::future_status::ready);
  // Road a is now stored and its checkpoint removed, as the BEV builder does when a road closes.
  EXPECT_TRUE(bev::removeCheckpoint(store.str(), a));
  writer->drain();
  const auto loaded = bev::loadCheckpoints(store.str());
  ASSERT_EQ(loaded.size(), 1u);  // a's queued 7-frame write never landed after the removal
  EXPECT_EQ(loaded[0].road_id, b);
  EXPECT_EQ(loaded[0].grid.frames(), 4);  // the newest asked
  EXPECT_EQ(loaded[0].last_frame_utime, 4);
  const auto s = writer->stats();
  EXPECT_EQ(s.written, 2);  // a's first, b's newest
  EXPECT_EQ(s.failed, 0);
  EXPECT_GT(s.kb, 0);
  // A write that fails (the store's folder is a file now) is counted and named, not thrown.
  lt::TempDir bad("checkpoint_writer_bad");
  { std::ofstream(bad.str("bev")) << "a file where the folder should be"; }
  bev::CheckpointWriter failing(bad.str());
  failing.write(roadWithEvidence(sk, a, 1), 1);
  failing.drain();
  EXPECT_EQ(failing.stats().failed, 1);
  const auto errors = failing.takeErrors();
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("road " + std::to_string(a)), std::string::npos) << errors[0];
  // The destructor writes what is still waiting.
  writer->write(roadWithEvidence(sk, b, 9), 9);
  writer.reset();
  const auto after = bev::loadCheckpoints(store.str());
  ASSERT_EQ(after.size(), 1u);
  EXPECT_EQ(after[0].grid.frames(), 9);
}
