// IV-A: the Z-ridge, of observed points and of the posed model.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>

#include "locate/locator.hpp"
#include "locate_fixtures.hpp"

namespace pipeloc {
namespace {

// IV-A: the Z-ridge of a horizontal cylinder's surface is its top line: one point per line
// across the axis, at the top of the tube and over its axis.
TEST(ZRidge, OfAHorizontalCylinderIsItsTopLine) {
  const float radius = 10, length = 200;
  const Eigen::Vector2f axis = Eigen::Vector2f(1, 1).normalized();
  std::vector<Eigen::Vector3f> pts;
  for (float s = 0; s <= length; s += 0.5f)
    for (int k = 0; k < 72; ++k) {
      const float a = float(k) * float(M_PI) / 36;
      const Eigen::Vector2f across(-axis.y(), axis.x());
      const Eigen::Vector2f xy = s * axis + radius * std::cos(a) * across;
      pts.emplace_back(xy.x(), xy.y(), 500 + radius * std::sin(a));
    }
  RidgeBuffers rb;
  reserve_ridge(&rb, length + 4 * radius, 2.0f, int(pts.size()));
  std::vector<Eigen::Vector3f> ridge(400);
  const int n = extract_zridge(pts.data(), int(pts.size()), axis, 2.0f, 0.6f * radius, &rb, ridge.data(),
                               int(ridge.size()));
  EXPECT_GE(n, int(length / 2) - 2);
  EXPECT_LE(n, int(length / 2) + 2);
  for (int i = 0; i < n; ++i) {
    EXPECT_NEAR(ridge[std::size_t(i)].z(), 500 + radius, 0.1);
    const Eigen::Vector2f xy = ridge[std::size_t(i)].head<2>();
    EXPECT_NEAR(xy.x() * axis.y() - xy.y() * axis.x(), 0, 1.0) << "off the axis line";
  }
}

// Points are binned four at a time when the buffers hold them all, one at a time when not: the
// same ridge either way, also when the grid is smaller than the points' span and drops some.
TEST(ZRidge, BinnedFourAtATimeAsOneAtATime) {
  const float radius = 10, length = 300;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1, 1);
  std::vector<Eigen::Vector3f> pts;
  for (int k = 0; k < 20003; ++k) {  // not a multiple of four
    const float s = (u(rng) + 1) * length / 2, a = u(rng) * float(M_PI);
    pts.emplace_back(s, radius * std::cos(a) + 0.2f * s, 500 + radius * std::sin(a));
  }
  for (const float extent : {length + 4 * radius, length / 2}) {  // the grid holds the span, or half
    RidgeBuffers four, one;
    reserve_ridge(&four, extent, 2.0f, int(pts.size()));
    reserve_ridge(&one, extent, 2.0f, 100);
    std::vector<Eigen::Vector3f> a(1000), b(1000);
    const Eigen::Vector2f axis = Eigen::Vector2f(1, 0.2f).normalized();
    const int n = extract_zridge(pts.data(), int(pts.size()), axis, 2.0f, 6, &four, a.data(), 1000);
    const int m = extract_zridge(pts.data(), int(pts.size()), axis, 2.0f, 6, &one, b.data(), 1000);
    ASSERT_EQ(n, m) << "extent " << extent;
    EXPECT_GT(n, int(extent / 2 / 4)) << "extent " << extent;
    for (int i = 0; i < n; ++i) ASSERT_EQ(a[std::size_t(i)], b[std::size_t(i)]) << "extent " << extent;
  }
}

// The model's samples by coordinate (four at a time) give the same ridge, point for point, as the
// samples one at a time, at any pose and in both ridge cells.
TEST(ZRidge, ColumnsGiveTheSameRidgeAsPoints) {
  LocateConfig cfg;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (const char* name : {"sbend", "u", "torus"}) {
    const LocatorModel lm = prepare_locator_model(preset_model(name), 8, cfg);
    RidgeBuffers rb;
    reserve_ridge(&rb, lm.extent_l_mm + 2 * lm.tube_d_mm, float(cfg.ridge_cell_mm),
                  int(lm.ridge_samples.size()));
    std::vector<Eigen::Vector3f> by_points(2000), by_columns(2000);
    for (const float cell : {float(cfg.ridge_cell_mm), float(cfg.icp_probe_cell_mm)}) {
      int ridge_points = 0;
      PosedPoints pp;
      pp.points = lm.ridge_samples.data();
      pp.normals = lm.ridge_normals.data();
      pp.count = int(lm.ridge_samples.size());
      pp.stride = ridge_sample_stride(cell, cfg);
      ASSERT_NE(lm.ridge_columns_for(pp.stride), nullptr) << name << " " << cell;
      for (int trial = 0; trial < 40; ++trial) {
        pp.to_bin = Pose::Identity();
        pp.to_bin.linear() = (Eigen::AngleAxisd(u(rng) * M_PI, Eigen::Vector3d::UnitZ()) *
                              Eigen::AngleAxisd(u(rng) * M_PI, Eigen::Vector3d::UnitX()) *
                              Eigen::AngleAxisd(u(rng) * 0.5, Eigen::Vector3d::UnitY()))
                                 .toRotationMatrix();
        pp.to_bin.translation() = Eigen::Vector3d(u(rng) * 300, u(rng) * 300, 800);
        const double a = u(rng) * M_PI;
        const Eigen::Vector2f axis(float(std::cos(a)), float(std::sin(a)));
        pp.columns = nullptr;
        const int n = extract_zridge(pp, axis, cell, 0.3f * lm.tube_d_mm, &rb, by_points.data(), 2000);
        pp.columns = lm.ridge_columns_for(pp.stride);
        const int m = extract_zridge(pp, axis, cell, 0.3f * lm.tube_d_mm, &rb, by_columns.data(), 2000);
        ASSERT_EQ(n, m) << name << " cell " << cell << " trial " << trial;
        ridge_points += n;
        for (int i = 0; i < n; ++i) ASSERT_EQ(by_points[std::size_t(i)], by_columns[std::size_t(i)]);
      }
      EXPECT_GT(ridge_points, 40 * 10) << name << " cell " << cell << ": the poses hide the ridge";
    }
  }
}

}  // namespace
}  // namespace pipeloc
