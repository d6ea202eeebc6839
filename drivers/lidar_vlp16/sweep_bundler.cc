// Sweep bundling of Velodyne packets (see sweep_bundler.h).
#include "drivers/lidar_vlp16/sweep_bundler.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace lanemap::drivers {

const char* modelDisplayName(lidar::Model model) {
  switch (model) {
    case lidar::Model::kVlp16:
      return "VLP-16";
    case lidar::Model::kVlp32c:
      return "VLP-32C";
    case lidar::Model::kHdl32e:
      return "HDL-32E";
  }
  return "unknown";
}

std::string rejectionCounterName(lidar::DecodeStatus status) {
  switch (status) {
    case lidar::DecodeStatus::kOk:
      return "packets";
    case lidar::DecodeStatus::kShort:
      return "rejected_short";
    case lidar::DecodeStatus::kOversize:
      return "rejected_oversize";
    case lidar::DecodeStatus::kBadFlag:
      return "rejected_bad_flag";
    case lidar::DecodeStatus::kBadAzimuth:
      return "rejected_bad_azimuth";
    case lidar::DecodeStatus::kUnknownReturnMode:
      return "rejected_unknown_return_mode";
    case lidar::DecodeStatus::kUnknownModel:
      return "rejected_unknown_model";
  }
  return "rejected_other";
}

SweepBundler::SweepBundler(std::optional<lidar::Model> forced_model, bool keep_points)
    : decoder_(forced_model), keep_points_(keep_points) {}

lidar::DecodeStatus SweepBundler::add(const uint8_t* data, std::size_t size, int64_t receive_utime,
                                      std::vector<PacketSweep>& done) {
  scratch_.clear();
  lidar::PacketInfo info;
  const lidar::DecodeStatus status = decoder_.decode(data, size, scratch_, &info);
  if (status != lidar::DecodeStatus::kOk) return status;

  current_.model = info.model;
  current_.packets.emplace_back();
  std::memcpy(current_.packets.back().data(), data, lidar::kDataPacketSize);
  current_.packet_utime.push_back(receive_utime);

  // Sensor time of each firing (us past the hour, unwrapped) and the host-minus-sensor offset of
  // this packet: it arrives just after its last firing.
  if (last_usec_past_hour_ && info.usec_past_hour + 1800000000ULL < *last_usec_past_hour_) {
    hour_offset_us_ += 3600LL * 1000000;
  }
  last_usec_past_hour_ = info.usec_past_hour;
  const int64_t packet_us = hour_offset_us_ + info.usec_past_hour;
  float last_offset = 0.0f;
  for (const auto& p : scratch_) last_offset = std::max(last_offset, p.time_offset_s);
  const int64_t anchor = receive_utime - (packet_us + std::lround(last_offset * 1e6));
  for (const auto& p : scratch_) {
    pending_point_sensor_us_.push_back(packet_us + std::lround(p.time_offset_s * 1e6));
    pending_point_anchor_us_.push_back(anchor);
  }
  pending_points_.insert(pending_points_.end(), scratch_.begin(), scratch_.end());

  if (splitter_.add(scratch_) == 0) {
    if (current_.packets.size() >= kMaxPacketsPerSweep) {  // no wrap: start over, like at start-up
      ++overlong_;
      finish();
      splitter_ = lidar::SweepSplitter{};
      seen_wrap_ = false;
    }
    return status;
  }
  // The azimuth wrapped in this packet: it ends the packet sweep; the splitter's completed
  // rotation(s) are the first points of the pending ones.
  std::size_t used = 0;
  std::vector<lidar::LidarPoint> rotation;
  std::vector<int64_t> rotation_utime;
  for (auto& sweep : splitter_.takeSweeps()) {
    const std::size_t n = std::min(sweep.size(), pending_points_.size() - used);
    rotation.assign(pending_points_.begin() + used, pending_points_.begin() + used + n);
    rotation_utime.clear();
    for (std::size_t i = used; i < used + n; ++i) {
      rotation_utime.push_back(pending_point_sensor_us_[i] + pending_point_anchor_us_[used]);
    }
    used += n;
  }
  pending_points_.erase(pending_points_.begin(), pending_points_.begin() + used);
  pending_point_sensor_us_.erase(pending_point_sensor_us_.begin(),
                                 pending_point_sensor_us_.begin() + used);
  pending_point_anchor_us_.erase(pending_point_anchor_us_.begin(),
                                 pending_point_anchor_us_.begin() + used);

  if (seen_wrap_) {
    if (keep_points_) {
      current_.points = std::move(rotation);
      current_.point_utime = std::move(rotation_utime);
    }
    done.push_back(std::move(current_));
  } else {
    ++partial_;  // started mid-rotation
  }
  seen_wrap_ = true;
  current_ = PacketSweep{};
  return status;
}

void SweepBundler::finish() {
  if (!current_.packets.empty()) ++partial_;
  current_ = PacketSweep{};
  pending_points_.clear();
  pending_point_sensor_us_.clear();
  pending_point_anchor_us_.clear();
}

}  // namespace lanemap::drivers
