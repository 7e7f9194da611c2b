// A live depth sensor through OpenNI2 (PrimeSense / ASUS Xtion), or its "Dummy" device where no
// sensor is attached. A lost device gives sensor_unavailable and is reopened, at most once per
// source.openni2.reopen_interval_ms, on the following grabs; cycles resume when it is back.
#pragma once

#include <memory>

#include "service/frame_source.hpp"

namespace pipeloc {

class OpenNi2Source : public FrameSource {
 public:
  explicit OpenNi2Source(const OpenNi2SourceConfig& cfg);  // throws SourceError if it cannot open
  ~OpenNi2Source() override;
  const char* kind() const override { return "openni2"; }
  const Intrinsics& intrinsics() const override { return intrinsics_; }
  GrabStatus grab(Clock::time_point after, Clock::time_point deadline, Frame* out) override;
  std::string describe() const override;

 private:
  struct Device;
  bool open(std::string* why);
  void close();

  OpenNi2SourceConfig cfg_;
  std::unique_ptr<Device> dev_;
  Intrinsics intrinsics_;
  std::string device_name_;
  Clock::time_point last_open_attempt_{};
  std::uint64_t sequence_ = 0;
  Pose world_to_cam_ = Pose::Identity();  // source.openni2.world_to_cam, when given
};

}  // namespace pipeloc
