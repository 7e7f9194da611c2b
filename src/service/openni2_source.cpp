#include "service/openni2_source.hpp"

#include <OpenNI.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <thread>

namespace pipeloc {

struct OpenNi2Source::Device {
  openni::Device device;
  openni::VideoStream depth;
  openni::VideoFrameRef frame;
  bool open = false;
};

OpenNi2Source::OpenNi2Source(const OpenNi2SourceConfig& cfg) : cfg_(cfg), dev_(std::make_unique<Device>()) {
  if (cfg.world_to_cam.size() == 16) world_to_cam_ = pose_from_matrix_rowmajor(cfg.world_to_cam.data());
  // OpenNI::shutdown() is never called: Debian's OpenNI2 2.2.0.33 crashes in it once a driver
  // thread has run; the process exit releases the device.
  if (openni::OpenNI::initialize() != openni::STATUS_OK)
    throw SourceError(std::string("source.openni2: OpenNI2 did not initialize: ") +
                      openni::OpenNI::getExtendedError());
  std::string why;
  if (!open(&why)) throw SourceError("source.openni2.uri '" + cfg.uri + "': " + why);
}

OpenNi2Source::~OpenNi2Source() { close(); }

bool OpenNi2Source::open(std::string* why) {
  last_open_attempt_ = Clock::now();
  Device& d = *dev_;
  const char* uri = cfg_.uri.empty() ? openni::ANY_DEVICE : cfg_.uri.c_str();
  if (d.device.open(uri) != openni::STATUS_OK) {
    *why = std::string("cannot open the device: ") + openni::OpenNI::getExtendedError();
    return false;
  }
  if (d.depth.create(d.device, openni::SENSOR_DEPTH) != openni::STATUS_OK) {
    *why = std::string("no depth stream: ") + openni::OpenNI::getExtendedError();
    d.device.close();
    return false;
  }
  // 640x480 in mm where the device offers it; otherwise the mode it runs (the Dummy: 320x240).
  const auto& modes = d.depth.getSensorInfo().getSupportedVideoModes();
  for (int i = 0; i < modes.getSize(); ++i)
    if (modes[i].getResolutionX() == 640 && modes[i].getResolutionY() == 480 &&
        modes[i].getPixelFormat() == openni::PIXEL_FORMAT_DEPTH_1_MM) {
      d.depth.setVideoMode(modes[i]);
      break;
    }
  const openni::VideoMode mode = d.depth.getVideoMode();
  if (mode.getPixelFormat() != openni::PIXEL_FORMAT_DEPTH_1_MM &&
      mode.getPixelFormat() != openni::PIXEL_FORMAT_DEPTH_100_UM) {
    *why = "the depth stream is neither in 1 mm nor in 100 um units";
    d.depth.destroy();
    d.device.close();
    return false;
  }
  if (d.depth.start() != openni::STATUS_OK) {
    *why = std::string("depth stream did not start: ") + openni::OpenNI::getExtendedError();
    d.depth.destroy();
    d.device.close();
    return false;
  }
  Intrinsics k;
  k.width = mode.getResolutionX();
  k.height = mode.getResolutionY();
  const double hfov = d.depth.getHorizontalFieldOfView(), vfov = d.depth.getVerticalFieldOfView();
  if (hfov > 0.01 && vfov > 0.01) {  // the device knows its optics
    k.fx = k.width / 2.0 / std::tan(hfov / 2);
    k.fy = k.height / 2.0 / std::tan(vfov / 2);
    k.cx = (k.width - 1) / 2.0;
    k.cy = (k.height - 1) / 2.0;
  } else {  // the Dummy device reports FOV 0: the configured calibration, scaled to this size
    const double sx = double(k.width) / cfg_.calib_width, sy = double(k.height) / cfg_.calib_height;
    k.fx = cfg_.fx * sx;
    k.fy = cfg_.fy * sy;
    k.cx = (cfg_.cx + 0.5) * sx - 0.5;
    k.cy = (cfg_.cy + 0.5) * sy - 0.5;
  }
  if (sequence_ > 0 && (k.width != intrinsics_.width || k.height != intrinsics_.height)) {
    *why = "the device came back with another resolution";
    close();
    return false;
  }
  intrinsics_ = k;
  device_name_ = d.device.getDeviceInfo().getName();
  if (device_name_.empty()) device_name_ = d.device.getDeviceInfo().getUri();
  d.open = true;
  return true;
}

void OpenNi2Source::close() {
  Device& d = *dev_;
  if (!d.open) return;
  d.frame.release();
  d.depth.stop();
  // Debian's OpenNI2 2.2.0.33: the Dummy driver's frame thread does not stop with the stream and
  // can call into a destroyed one (a crash, reproduced); a few frame periods let it finish.
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  d.depth.destroy();
  d.device.close();
  d.open = false;
}

GrabStatus OpenNi2Source::grab(Clock::time_point after, Clock::time_point deadline, Frame* out) {
  Device& d = *dev_;
  if (!d.open) {
    if (Clock::now() - last_open_attempt_ < std::chrono::milliseconds(cfg_.reopen_interval_ms))
      return GrabStatus::sensor_unavailable;
    std::string why;
    if (!open(&why)) {
      spdlog::warn("openni2: device still unavailable: {}", why);
      return GrabStatus::sensor_unavailable;
    }
    spdlog::info("openni2: device back ({})", device_name_);
  }
  openni::VideoStream* streams[] = {&d.depth};
  int ready = -1;
  // Frames queued before the trigger are dropped: a LOCATE works on a frame taken after it.
  while (openni::OpenNI::waitForAnyStream(streams, 1, &ready, 0) == openni::STATUS_OK)
    if (d.depth.readFrame(&d.frame) != openni::STATUS_OK) break;
  (void)after;  // the drain above leaves only frames that arrive from now on
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
  const int wait_ms = int(std::max<long long>(1, std::min<long long>(left, cfg_.frame_timeout_ms)));
  if (openni::OpenNI::waitForAnyStream(streams, 1, &ready, wait_ms) != openni::STATUS_OK ||
      d.depth.readFrame(&d.frame) != openni::STATUS_OK) {
    if (wait_ms >= cfg_.frame_timeout_ms) {  // a whole timeout without a frame: the device is gone
      spdlog::warn("openni2: no frame in {} ms: {}; reopening", wait_ms, openni::OpenNI::getExtendedError());
      close();
    }
    return GrabStatus::sensor_unavailable;
  }
  out->captured = Clock::now();
  const int w = d.frame.getWidth(), h = d.frame.getHeight();
  if (w != intrinsics_.width || h != intrinsics_.height || out->depth_mm.width != w ||
      out->depth_mm.height != h || d.frame.getDataSize() < int(sizeof(std::uint16_t)) * w * h)
    return GrabStatus::frame_invalid;
  const double unit_mm =
      d.frame.getVideoMode().getPixelFormat() == openni::PIXEL_FORMAT_DEPTH_100_UM ? 0.1 : 1.0;
  const auto* raw = static_cast<const std::uint16_t*>(d.frame.getData());
  const int stride = d.frame.getStrideInBytes() / int(sizeof(std::uint16_t));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) out->depth_mm.at(x, y) = float(raw[std::size_t(y) * stride + x] * unit_mm);
  out->camera.intrinsics = intrinsics_;
  out->camera.depth_scale = 1.0;
  if (cfg_.world_to_cam.size() == 16) {
    out->camera.world_to_cam = world_to_cam_;
  } else {
    out->camera.world_to_cam.reset();
  }
  out->sequence = ++sequence_;
  out->scene_id = 0;
  out->im_id = d.frame.getFrameIndex();
  return GrabStatus::ok;
}

std::string OpenNi2Source::describe() const {
  return "openni2: " + device_name_ + " (uri \"" + cfg_.uri + "\"), " + std::to_string(intrinsics_.width) +
         "x" + std::to_string(intrinsics_.height) + ", fx " + std::to_string(intrinsics_.fx) + " fy " +
         std::to_string(intrinsics_.fy) +
         (cfg_.world_to_cam.size() == 16 ? ", bin frame from config" : ", camera frame");
}

}  // namespace pipeloc
