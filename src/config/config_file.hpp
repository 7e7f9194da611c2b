// The TOML configuration, validated once at start-up: an unknown key, a wrong type or a value
// out of range stops the program with a message naming the file, the key and what was expected.
// Every value in effect (given or default) is listed for the start-up log.
#pragma once

#include <array>
#include <stdexcept>
#include <string>
#include <vector>

#include "locate/locate_config.hpp"
#include "plc/register_map.hpp"

namespace pipeloc {

struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct ModelConfig {
  std::string stl;                         // path, relative to the config file; or ...
  std::string preset;                      // ... a built-in pipe (sbend, u, torus)
  std::array<double, 3> grasp_xyz_mm{};    // where the gripper closes, in the model frame
  std::array<double, 3> grasp_rxyz_deg{};  // its rotation, in plc.euler's convention
};

struct SimSourceConfig {
  int pipes = 20;
  int seed = 1;
  double tilt_deg = 0;  // camera tilt from vertical, drawn in [0, this] per bin
  double camera_height_min_mm = 980, camera_height_max_mm = 1080;  // above the bin floor, drawn per bin
  bool camera_sees_bin = false;   // both raised alike, if needed, until every camera drawn sees the bin's rim
  std::string sensor = "kinect";  // kinect (structured light) | stereo (active stereo, RealSense D4xx)
  bool refill = true;             // a new bin when the last pipe has been picked
  int refill_after_frames_without_pick = 0;  // ... or after this many frames in a row without one (0: never)
  bool shake_after_none = false;  // a LOCATE after a DONE_NONE finds the pipes left dropped again (a shaker)
  std::string truth_file;  // if set: one JSON line per frame with every pipe's true pose (tests, demo)
};

struct ReplaySourceConfig {
  std::string path;       // a BOP dataset (test/SSSSSS/depth/*.png) or a folder of depth PNGs
  std::string camera;     // scene_camera.json for a folder of PNGs (its first entry serves all)
  int max_frames = 1000;  // frames held in memory (read and checked at start-up)
};

struct OpenNi2SourceConfig {
  std::string uri;  // "" = any device; "Dummy" = OpenNI2's fake device
  // Used when the device reports no field of view (the Dummy device): scaled to its resolution.
  double fx = 570.3, fy = 570.3, cx = 319.5, cy = 239.5;
  int calib_width = 640, calib_height = 480;
  int frame_timeout_ms = 500;        // no frame in this time: sensor unavailable
  int reopen_interval_ms = 1000;     // a lost device is reopened at most this often
  std::vector<double> world_to_cam;  // optional 16 values, row-major, mm: the bin frame (Z up)
};

struct SourceConfig {
  std::string kind = "sim";  // sim | replay | openni2
  SimSourceConfig sim;
  ReplaySourceConfig replay;
  OpenNi2SourceConfig openni2;
};

struct ServiceConfig {
  double budget_ms = 250;   // trigger to result; localization stops early to keep it
  int summary_every = 100;  // cycles between summary lines in the timing log
  // A pose handed out whose pick left the bin unchanged there is not handed out again while it
  // stays so (TriedPicks): the next pose, or DONE_NONE with the pose withheld as `took_nothing`.
  bool withhold_unchanged_picks = true;
};

struct PlcConfig {
  std::string mode = "server";  // server | client | none
  std::string address = "127.0.0.1";
  int port = 1502;
  int base = 0;                            // first holding register of the map
  int unit_id = 1;                         // client mode: the PLC's unit identifier
  int max_clients = 8;                     // server mode: connections served at once
  int request_timeout_ms = 500;            // server mode: a request not complete this long after its
                                           // first byte closes its connection
  int idle_timeout_ms = 60000;             // server mode: a connection without a request this long is closed
  std::vector<std::string> plc_addresses;  // server mode: the PLC's IPv4 addresses (never evicted
                                           // for another client)
  int poll_ms = 50;                        // client mode: how often CMD/REQ_ID are read
  int reconnect_max_ms = 5000;             // client mode: backoff cap
  int byte_timeout_ms = 100;               // client mode: the PLC's reply may pause this long between bytes
  bool write_held = false;  // client mode: also write HELD, HELD_WHY, REGIONS (42-44); off, a PLC
                            // block programmed for 0-41 is never written beyond it
  reg::Encoding encoding;
  EulerConvention euler = EulerConvention::zyx;
  std::vector<double> robot_from_camera;  // optional 16 values, row-major, mm: hand-eye
};

struct LogConfig {
  std::string dir = "pipeloc-log";  // timing log folder, relative to the working directory
  int max_file_kb = 10240;          // a log file is rotated beyond this size
  int keep_files = 5;               // rotated files kept (timing.jsonl.1 .. .N)
  int overlay_every = 0;            // every N-th LOCATE: overlay-latest.png in dir (0 = never)
  int no_pick_frames = 10;          // the last N LOCATEs handing out no pose kept in dir/no-pick (0 = none)
  int took_nothing_frames = 10;     // the last N picks that took nothing kept in dir/took-nothing (0 = none)
};

// The status page and /metrics (src/status): off unless enabled; served on a thread of its own.
struct StatusConfig {
  bool enabled = false;
  std::string address = "127.0.0.1";  // IPv4; "0.0.0.0" serves every interface
  int port = 8080;                    // 0: any free port (the log says which)
  int overlay_every = 1;              // every N-th LOCATE's overlay is drawn for the page (0 = none)
  int refresh_s = 3;                  // the page reloads itself this often
};

struct AppConfig {
  std::string path;        // the file it came from ("" = built-in defaults)
  std::string model_path;  // = model.stl resolved; kept for the offline commands
  ModelConfig model;
  LocateConfig locate;
  SourceConfig source;
  ServiceConfig service;
  PlcConfig plc;
  LogConfig log;
  StatusConfig status;
  std::vector<std::string> effective;  // "section.key = value  # unit" for every value in effect
  std::vector<std::string> warnings;   // keys given that the chosen mode or source ignores
};

AppConfig load_config(const std::string& path);
// The built-in defaults, as if from an empty file.
AppConfig default_config();
// What runs without --config: the defaults with the S-bend preset as the pipe (a simulated bin,
// Modbus server on 127.0.0.1:1502; config/demo.toml spells it out).
AppConfig embedded_default_config();
// Every value in effect, one "section.key = value" line each, for the start-up log.
std::vector<std::string> describe_config(const AppConfig& cfg);

}  // namespace pipeloc
