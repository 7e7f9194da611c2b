// IV-A: the Z-ridge, of observed points and of the posed model.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
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

// The ridge read off the grid equals one read cell by cell from a plain map of the cells: per line
// across the axis, per run of occupied cells (one empty cell allowed), the highest point, where it
// is neither end of its run. Seven tubes side by side, a row spanning three 64-cell words of the
// occupied bits, runs across the words' borders, holes; the axis along x, so that the points' own
// coordinates are the grid's.
TEST(ZRidge, EveryRunOfEveryLineAsReadCellByCell) {
  const float cell = 2.0f, min_run = 6.0f;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<Eigen::Vector3f> pts;
  for (int tube = 0; tube < 7; ++tube) {
    const float radius = 6.0f + 2.0f * float(tube), y0 = 45.0f * float(tube);
    for (int k = 0; k < 6000; ++k) {
      const float x = 300 * u(rng), a = float(M_PI) * u(rng);
      if (std::abs(x - 40 * float(tube + 1)) < 8) continue;  // a hole across the tube
      pts.emplace_back(x, y0 + radius * std::cos(a), 400 + 5 * float(tube) + radius * std::sin(a));
    }
  }
  RidgeBuffers rb;
  reserve_ridge(&rb, 400, cell, int(pts.size()));
  std::vector<Eigen::Vector3f> ridge(4000);
  const int n = extract_zridge(pts.data(), int(pts.size()), Eigen::Vector2f(1, 0), cell, min_run, &rb,
                               ridge.data(), int(ridge.size()));

  float u0 = 1e30f, v0 = 1e30f, u1 = -1e30f, v1 = -1e30f;
  for (const auto& p : pts)
    u0 = std::min(u0, p.x()), v0 = std::min(v0, p.y()), u1 = std::max(u1, p.x()), v1 = std::max(v1, p.y());
  const float inv = 1.0f / cell;
  const int rows = int((u1 - u0) / cell) + 1, cols = int((v1 - v0) / cell) + 1;
  ASSERT_GT(cols, 128) << "the rows should span three words";
  std::map<std::pair<int, int>, int> top;  // (row, column) -> the first highest point's index
  for (int k = 0; k < int(pts.size()); ++k) {
    const int r = int((pts[std::size_t(k)].x() - u0) * inv), c = int((pts[std::size_t(k)].y() - v0) * inv);
    const auto it = top.find({r, c});
    if (it == top.end() || pts[std::size_t(k)].z() > pts[std::size_t(it->second)].z()) top[{r, c}] = k;
  }
  std::vector<Eigen::Vector3f> expected;
  for (int r = 0; r < rows; ++r) {
    std::vector<std::pair<int, int>> line;  // (column, point) of the occupied cells, in order
    for (auto it = top.lower_bound({r, 0}); it != top.end() && it->first.first == r; ++it)
      line.emplace_back(it->first.second, it->second);
    for (std::size_t a = 0; a < line.size();) {
      std::size_t b = a, best = a;
      while (b + 1 < line.size() && line[b + 1].first - line[b].first <= 2) {
        ++b;
        if (pts[std::size_t(line[b].second)].z() > pts[std::size_t(line[best].second)].z()) best = b;
      }
      if (line[b].first - line[a].first + 1 >= int(min_run / cell) && best != a && best != b)
        expected.push_back(pts[std::size_t(line[best].second)]);
      a = b + 1;
    }
  }
  ASSERT_EQ(n, int(expected.size()));
  EXPECT_GT(n, 7 * 100) << "a ridge point per line of each tube, less the holes";
  for (int i = 0; i < n; ++i) ASSERT_EQ(ridge[std::size_t(i)], expected[std::size_t(i)]) << "point " << i;
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
