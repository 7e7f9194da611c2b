#include <gtest/gtest.h>

#include <fstream>

#include "io/bop.hpp"
#include "io/png.hpp"
#include "io/results_csv.hpp"
#include "render/text.hpp"
#include "test_util.hpp"

namespace pipeloc {
namespace {

using test::TempDir;

template <typename F>
std::string error_of(F f) {
  try {
    f();
  } catch (const IoError& e) {
    return e.what();
  }
  return "";
}

TEST(DepthPng, RoundTripWithScale) {
  TempDir dir;
  Image<std::uint16_t> raw(7, 5, 0);
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 7; ++x) raw.at(x, y) = std::uint16_t(1000 + 100 * y + x);
  raw.at(3, 2) = 65535;
  write_depth_png(dir.file("d.png"), raw);
  const auto back = read_depth_png(dir.file("d.png"));
  ASSERT_EQ(back.width, 7);
  ASSERT_EQ(back.height, 5);
  EXPECT_EQ(back.pixels, raw.pixels);
  const auto mm = read_depth_mm(dir.file("d.png"), 0.1);
  EXPECT_FLOAT_EQ(mm.at(1, 1), 110.1f);
}

TEST(DepthPng, BadFilesAreNamed) {
  TempDir dir;
  EXPECT_NE(error_of([&] { read_depth_png(dir.file("missing.png")); }).find("cannot open"),
            std::string::npos);
  test::write_text(dir.file("text.png"), "this is not a png at all");
  EXPECT_NE(error_of([&] { read_depth_png(dir.file("text.png")); }).find("not a PNG"), std::string::npos);
  Image<Rgb> rgb(4, 4);
  write_rgb_png(dir.file("rgb.png"), rgb);
  const std::string msg = error_of([&] { read_depth_png(dir.file("rgb.png")); });
  EXPECT_NE(msg.find("16-bit"), std::string::npos) << msg;
  EXPECT_NE(msg.find("rgb.png"), std::string::npos) << msg;
  Image<std::uint16_t> raw(64, 64, 1234);
  for (std::size_t i = 0; i < raw.pixels.size(); ++i) raw.pixels[i] = std::uint16_t(i * 7919);
  write_depth_png(dir.file("ok.png"), raw);
  const std::string bytes = test::read_text(dir.file("ok.png"));
  test::write_text(dir.file("cut.png"), bytes.substr(0, bytes.size() / 2));
  EXPECT_NE(error_of([&] { read_depth_png(dir.file("cut.png")); }).find("cut.png"), std::string::npos);
}

TEST(SceneCamera, WithAndWithoutExtrinsics) {
  TempDir dir;
  test::write_text(dir.file("c.json"), R"({
    "0": {"cam_K": [570, 0, 320, 0, 571, 240, 0, 0, 1], "depth_scale": 0.5},
    "3": {"cam_K": [570, 0, 320, 0, 571, 240, 0, 0, 1], "depth_scale": 1.0,
          "cam_R_w2c": [1, 0, 0, 0, -1, 0, 0, 0, -1], "cam_t_w2c": [1, 2, 1000]}})");
  const auto cams = read_scene_camera(dir.file("c.json"));
  ASSERT_EQ(cams.size(), 2u);
  EXPECT_FALSE(cams.at(0).world_to_cam.has_value());
  EXPECT_DOUBLE_EQ(cams.at(0).depth_scale, 0.5);
  EXPECT_DOUBLE_EQ(cams.at(0).intrinsics.fy, 571);
  ASSERT_TRUE(cams.at(3).world_to_cam.has_value());
  EXPECT_NEAR((*cams.at(3).world_to_cam * Eigen::Vector3d(0, 0, 0)).z(), 1000, 1e-9);
  EXPECT_NEAR((cams.at(3).world_to_cam->linear() * Eigen::Vector3d::UnitZ()).z(), -1, 1e-9);
}

TEST(SceneCamera, BadFilesNameTheField) {
  TempDir dir;
  const auto check = [&](const std::string& text, const std::string& expect) {
    test::write_text(dir.file("c.json"), text);
    const std::string msg = error_of([&] { read_scene_camera(dir.file("c.json")); });
    EXPECT_NE(msg.find(expect), std::string::npos) << "got: " << msg;
    EXPECT_NE(msg.find("c.json"), std::string::npos) << "got: " << msg;
  };
  check("{ not json", "not valid JSON");
  check(R"({"0": {"depth_scale": 1}})", "cam_K");
  check(R"({"0": {"cam_K": [1, 2, 3], "depth_scale": 1}})", "expected 9 numbers");
  check(R"({"0": {"cam_K": [570, 0, 320, 0, 570, 240, 0, 0, 1], "depth_scale": -1}})", "depth_scale");
  check(
      R"({"0": {"cam_K": [570, 0, 320, 0, 570, 240, 0, 0, 1], "depth_scale": 1, "cam_R_w2c": [1,0,0,0,1,0,0,0,1]}})",
      "come together");
  check(R"({"x": {"cam_K": [570, 0, 320, 0, 570, 240, 0, 0, 1], "depth_scale": 1}})", "not an image id");
  check(R"([1, 2])", "expected a JSON object");
}

TEST(ResultsCsv, WritesAndReadsAndCountsMalformedRows) {
  TempDir dir;
  {
    std::ofstream out(dir.file("r.csv"));
    write_results_header(out);
    ResultRow row;
    row.scene_id = 2;
    row.im_id = 5;
    row.obj_id = 1;
    row.score = 0.75;
    row.model_to_cam.linear() =
        Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    row.model_to_cam.translation() = Eigen::Vector3d(10, -20, 1000);
    row.time_s = 0.031;
    write_result_row(out, row);
    out << "1,2,3\n";                                  // too few fields
    out << "1,2,3,0.5,1 0 0 0 1 0 0 0 1,1 2,0.1\n";    // t has 2 values
    out << "1,2,3,abc,1 0 0 0 1 0 0 0 1,1 2 3,0.1\n";  // score not a number
    out << "1,2,3,0.5,2 0 0 0 1 0 0 0 1,1 2 3,0.1\n";  // not a rotation
  }
  const ResultsFile file = read_results_csv(dir.file("r.csv"));
  ASSERT_EQ(file.rows.size(), 1u);
  EXPECT_EQ(file.malformed, 4);
  EXPECT_EQ(file.rows[0].im_id, 5);
  EXPECT_NEAR(file.rows[0].model_to_cam.translation().z(), 1000, 1e-6);
  EXPECT_NEAR(file.rows[0].time_s, 0.031, 1e-9);
  EXPECT_NE(file.first_errors[0].find("line 3"), std::string::npos) << file.first_errors[0];
}

// A pose's label on the overlay is read whole: a pose at the image's edge (its centre near or
// beyond it) has its label moved into the image, and one under the legend moved off it.
TEST(OverlayLabel, LiesWhollyInTheImageAndOffTheLegend) {
  const int width = 640, height = 480, scale = 2;
  const std::string text = "R4 0.42 AMBIGUOUS";
  const int w = int(text.size()) * 4 * scale + scale, h = 7 * scale;
  const PixelBox legend{4, 4, 221, 151}, none;
  auto inside = [&](const Eigen::Vector2i& at) {
    return at.x() - scale >= 0 && at.x() - scale + w <= width && at.y() - scale >= 0 &&
           at.y() - scale + h <= height;
  };
  auto clear_of = [&](const Eigen::Vector2i& at, const PixelBox& b) {
    return at.x() - scale > b.x1 || at.x() - scale + w - 1 < b.x0 || at.y() - scale > b.y1 ||
           at.y() - scale + h - 1 < b.y0;
  };
  // In the open: where it was asked.
  EXPECT_EQ(place_label(300, 300, text, width, height, legend), Eigen::Vector2i(300, 300));
  // Past the right edge, the bottom, the top-left corner; a centre far out of the view.
  for (const Eigen::Vector2i& asked : {Eigen::Vector2i(600, 300), Eigen::Vector2i(300, 475),
                                       Eigen::Vector2i(-50, -40), Eigen::Vector2i(5000, -9000)}) {
    const Eigen::Vector2i at = place_label(asked.x(), asked.y(), text, width, height, none);
    EXPECT_TRUE(inside(at)) << asked.transpose() << " -> " << at.transpose();
  }
  EXPECT_EQ(place_label(600, 300, text, width, height, none).y(), 300);  // moved along the edge only
  // Under the legend: moved the shorter way off it, still whole.
  for (const Eigen::Vector2i& asked : {Eigen::Vector2i(100, 140), Eigen::Vector2i(200, 40),
                                       Eigen::Vector2i(-30, 60), Eigen::Vector2i(10, 10)}) {
    const Eigen::Vector2i at = place_label(asked.x(), asked.y(), text, width, height, legend);
    EXPECT_TRUE(inside(at)) << asked.transpose() << " -> " << at.transpose();
    EXPECT_TRUE(clear_of(at, legend)) << asked.transpose() << " -> " << at.transpose();
  }
  EXPECT_EQ(place_label(100, 140, text, width, height, legend), Eigen::Vector2i(100, 152 + scale));
  EXPECT_EQ(place_label(215, 40, text, width, height, legend), Eigen::Vector2i(222 + scale, 40));
}

}  // namespace
}  // namespace pipeloc
