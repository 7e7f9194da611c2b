#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <atomic>
#include <chrono>
#include <cmath>
#include <random>
#include <thread>

#include "config/config_file.hpp"
#include "core/worker_pool.hpp"
#include "locate/locator.hpp"
#include "model/make_pipe.hpp"
#include "score/mssd.hpp"
#include "sim/scene.hpp"
#include "test_util.hpp"

namespace pipeloc {
namespace {

const PipeModel& preset_model(const std::string& name) {
  static std::map<std::string, PipeModel> models;
  auto it = models.find(name);
  if (it == models.end())
    it = models.emplace(name, derive_pipe_model(make_pipe(pipe_preset(name)), name)).first;
  return it->second;
}

double pose_error(const PipeModel& m, const Pose& a, const Pose& b) {
  std::vector<Eigen::Vector3d> v;
  for (const auto& p : m.mesh.vertices) v.push_back(p.cast<double>());
  return mssd(v, a, b, m.symmetries, 1e9);
}

// Fills a Z-buffer with z = f(x, y) on a 1 mm grid.
template <typename F>
ZBuffer synthetic_zbuffer(int size, F f) {
  ZBuffer zb;
  reserve_zbuffer(&zb, size, 1.0);
  zb.width = zb.height = size;
  for (int j = 0; j < size; ++j)
    for (int i = 0; i < size; ++i) zb.z.at(i, j) = f(double(i), double(j));
  return zb;
}

TEST(Normals, PlaneHasItsNormalEverywhere) {
  const Eigen::Vector3d n = Eigen::Vector3d(0.2, -0.3, 1).normalized();
  ZBuffer zb =
      synthetic_zbuffer(60, [&](double x, double y) { return float(100 - (n.x() * x + n.y() * y) / n.z()); });
  zb.z.at(30, 30) = ZBuffer::kEmpty;  // a hole does not disturb its neighbours
  NormalMap nm;
  reserve_normals(&nm, zb);
  compute_normals(zb, 7, 20, &nm);
  for (int j = 5; j < 55; j += 3)
    for (int i = 5; i < 55; i += 3) {
      if (i == 30 && j == 30) continue;
      EXPECT_GT(nm.n.at(i, j).cast<double>().dot(n), std::cos(0.5 * M_PI / 180)) << i << "," << j;
    }
  EXPECT_EQ(nm.n.at(30, 30), Eigen::Vector3f::Zero());
}

TEST(Normals, CylinderTopFollowsTheSurface) {
  const double r = 10, cy = 30;  // a horizontal cylinder along x, radius 10 mm
  ZBuffer zb = synthetic_zbuffer(60, [&](double, double y) {
    const double dy = y - cy;
    return std::abs(dy) < r ? float(std::sqrt(r * r - dy * dy)) : ZBuffer::kEmpty;
  });
  NormalMap nm;
  reserve_normals(&nm, zb);
  compute_normals(zb, 5, 10, &nm);
  for (int dy = -6; dy <= 6; dy += 2) {
    const Eigen::Vector3d truth(0, dy / r, std::sqrt(1 - dy * dy / (r * r)));
    EXPECT_GT(nm.n.at(30, int(cy) + dy).cast<double>().dot(truth), std::cos(4 * M_PI / 180)) << dy;
  }
}

// Every cell against a plain least-squares fit of its window (brute force), on a row width that
// leaves cells to the one-at-a-time path, with holes and an edge where windows run thin.
TEST(Normals, EveryCellMatchesABruteForcePlaneFit) {
  const double r = 12, cy = 31;
  ZBuffer zb = synthetic_zbuffer(63, [&](double x, double y) {
    const double dy = y - cy + 0.2 * x;
    if (int(x * 7 + y * 3) % 17 == 0) return ZBuffer::kEmpty;  // scattered dropouts
    return std::abs(dy) < r ? float(std::sqrt(r * r - dy * dy) + 0.05 * x) : ZBuffer::kEmpty;
  });
  const int window = 7, min_valid = 20, k = window / 2;
  NormalMap nm;
  reserve_normals(&nm, zb);
  compute_normals(zb, window, min_valid, &nm);
  int fitted = 0;
  for (int j = 0; j < zb.height; ++j)
    for (int i = 0; i < zb.width; ++i) {
      Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
      Eigen::Vector3d atz = Eigen::Vector3d::Zero();
      int n = 0;
      for (int v = j - k; v <= j + k; ++v)
        for (int u = i - k; u <= i + k; ++u) {
          if (u < 0 || v < 0 || u >= zb.width || v >= zb.height || std::isnan(zb.z.at(u, v))) continue;
          const Eigen::Vector3d row(u, v, 1);
          ata += row * row.transpose(), atz += row * double(zb.z.at(u, v)), ++n;
        }
      const Eigen::Vector3f got = nm.n.at(i, j);
      if (std::isnan(zb.z.at(i, j)) || n < min_valid || std::abs(ata.determinant()) < 1e-6) {
        if (std::isnan(zb.z.at(i, j)) || n < min_valid) {
          EXPECT_EQ(got, Eigen::Vector3f::Zero()) << i << "," << j;
        }
        continue;
      }
      const Eigen::Vector3d abc = ata.ldlt().solve(atz);
      const Eigen::Vector3d want = Eigen::Vector3d(-abc.x(), -abc.y(), 1).normalized();
      EXPECT_LT((got.cast<double>() - want).norm(), 1e-4) << i << "," << j;
      ++fitted;
    }
  EXPECT_GT(fitted, 63 * 10);
}

TEST(Normals, RowBandsGiveTheSameNormalsAsOnePass) {
  const double r = 10, cy = 30;
  ZBuffer zb = synthetic_zbuffer(60, [&](double x, double y) {
    const double dy = y - cy + 0.1 * x;
    return std::abs(dy) < r ? float(std::sqrt(r * r - dy * dy)) : ZBuffer::kEmpty;
  });
  NormalMap one, banded;
  reserve_normals(&one, zb);
  reserve_normals(&banded, zb, 3);
  compute_normals(zb, 7, 20, &one);
  const int cuts[] = {0, 17, 41, zb.height};
  for (int b = 0; b < 3; ++b) compute_normals_rows(zb, 7, 20, cuts[b], cuts[b + 1], b, &banded);
  for (int j = 0; j < zb.height; ++j)
    for (int i = 0; i < zb.width; ++i)
      EXPECT_LT((one.n.at(i, j) - banded.n.at(i, j)).norm(), 1e-5f) << i << "," << j;
}

// A frame of one pipe lying alone in the bin, with the sensor model's noise.
struct OnePipe {
  SimulatedScene scene;
  LocateConfig cfg;
};

OnePipe one_pipe(const std::string& preset, unsigned seed) {
  std::mt19937 rng(seed);
  SceneParams p;
  p.pile.pipes = 1;
  return {simulate_scene(preset_model(preset), p, rng), LocateConfig{}};
}

// III on the noisy frame against III on the ideal top view of the pipe at its true pose.
// Measured for the S-bend, where the cross-section count has one clear peak. For the U and the
// torus-like pipe the count is flat over tens of degrees even on ideal data (their median
// disagreement is 15 degrees, see the closing note of issue 3); the initial states absorb that
// by measuring the model the same way (LocatorModel::canonical_starts).
TEST(PrincipalAxis, WithinFiveDegreesOfTheIdealForTheSBend) {
  for (const char* name : {"sbend"}) {
    std::vector<double> errors;
    for (unsigned seed = 1; seed <= 5; ++seed) {
      OnePipe s = one_pipe(name, seed);
      Locator loc(preset_model(name), s.cfg, s.scene.camera.intrinsics);
      const LocateOutput& out = loc.locate(s.scene.depth_mm, s.scene.camera);
      if (out.traces.empty()) continue;
      const Eigen::Vector2f truth = top_view_axis(preset_model(name), s.scene.model_to_world[0], s.cfg).axis;
      errors.push_back(std::acos(std::min(1.0f, std::abs(truth.dot(out.traces[0].axis.axis)))) * 180 / M_PI);
    }
    // A lone pipe is found in most frames, and its direction agrees with the ideal one.
    ASSERT_GE(errors.size(), 3u) << name;
    std::sort(errors.begin(), errors.end());
    EXPECT_LT(errors[errors.size() / 2], 5.0) << name;
    EXPECT_LT(errors.back(), 15.0) << name;
  }
}

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

// IV-B: from the paper's ranges (about the axis up to +-70 degrees, 3 cm along it) the ridge
// ICP with refinement converges on the pipe.
// Against brute force: the first of the closest points, on sets of 0 to 13 points (every tail
// after the groups of four), drawn on a coarse grid so that ties are common.
TEST(PointColumns, NearestIsTheFirstOfTheClosestAsBruteForce) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> grid(-3, 3), near(-1, 1);
  PointColumns columns;
  columns.reserve(16);
  int ties = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int n = trial % 14;
    std::vector<Eigen::Vector3f> pts;
    for (int k = 0; k < n; ++k) pts.emplace_back(float(near(rng)), float(near(rng)), 0.5f * float(near(rng)));
    ASSERT_TRUE(columns.assign(pts.data(), n));
    const Eigen::Vector3f q(float(grid(rng)) + 0.5f, float(grid(rng)), 0.25f * float(grid(rng)));
    int want = -1, at_least = 0;
    float want_d2 = 1e30f;
    for (int k = 0; k < n; ++k) {
      const float d2 = (pts[std::size_t(k)] - q).squaredNorm();
      if (d2 < want_d2) want_d2 = d2, want = k;
    }
    for (int k = 0; k < n; ++k) at_least += (pts[std::size_t(k)] - q).squaredNorm() == want_d2;
    ties += at_least > 1;
    float got_d2 = 0;
    EXPECT_EQ(columns.nearest(q, &got_d2), want) << "trial " << trial;
    if (want >= 0) {
      EXPECT_EQ(got_d2, want_d2) << "trial " << trial;
    }
  }
  EXPECT_GT(ties, 20);  // the tie-break was put to the test
}

// Both ways from one pass: each answer is nearest()'s from that side, ties to the first included.
TEST(PointColumns, NearestBothWaysIsNearestFromEachSide) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> near(-1, 1);
  const auto draw = [&](int n) {
    std::vector<Eigen::Vector3f> pts;
    for (int k = 0; k < n; ++k) pts.emplace_back(float(near(rng)), float(near(rng)), 0.5f * float(near(rng)));
    return pts;
  };
  PointColumns b_columns, a_columns;
  b_columns.reserve(16);
  a_columns.reserve(16);
  for (int trial = 0; trial < 300; ++trial) {
    const int na = trial % 11, nb = (trial / 11) % 14;
    const std::vector<Eigen::Vector3f> a = draw(na), b = draw(nb);
    ASSERT_TRUE(b_columns.assign(b.data(), nb));
    ASSERT_TRUE(a_columns.assign(a.data(), na));
    std::vector<int> a_to(16), b_to(16);
    std::vector<float> a_d2(16), b_d2(16);
    b_columns.nearest_both_ways(a.data(), na, a_to.data(), a_d2.data(), b_to.data(), b_d2.data());
    for (int i = 0; i < na; ++i) {
      float d2 = 0;
      EXPECT_EQ(a_to[std::size_t(i)], b_columns.nearest(a[std::size_t(i)], &d2)) << "trial " << trial;
      EXPECT_EQ(a_d2[std::size_t(i)], d2) << "trial " << trial;
    }
    for (int j = 0; j < nb; ++j) {
      float d2 = 0;
      EXPECT_EQ(b_to[std::size_t(j)], a_columns.nearest(b[std::size_t(j)], &d2)) << "trial " << trial;
      if (na > 0) {
        EXPECT_EQ(b_d2[std::size_t(j)], d2) << "trial " << trial;
      }
    }
  }
}

// A bound only cuts short what lies beyond it: up to the bound the distance is the exact one, and
// beyond it the value returned lies beyond it too (models with and without symmetries).
TEST(PoseDistance, ExactUpToTheBoundAndBeyondItPastIt) {
  LocateConfig cfg;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (const char* name : {"sbend", "torus"}) {
    const LocatorModel lm = prepare_locator_model(preset_model(name), 8, cfg);
    int below = 0, beyond = 0;
    for (int trial = 0; trial < 400; ++trial) {
      Pose a = Pose::Identity(), b = Pose::Identity();
      a.linear() = Eigen::AngleAxisd(u(rng) * M_PI, Eigen::Vector3d(u(rng), u(rng), 1).normalized())
                       .toRotationMatrix();
      a.translation() = Eigen::Vector3d(u(rng), u(rng), u(rng)) * 100;
      const double scale = std::pow(10.0, 2 * u(rng) - 1);  // small and large moves
      b.linear() =
          Eigen::AngleAxisd(0.05 * scale * u(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix() * a.linear();
      b.translation() = a.translation() + Eigen::Vector3d(u(rng), u(rng), u(rng)) * 3 * scale;
      const float exact = pose_distance_mm(lm, a, b);
      for (const float bound : {1.0f, 5.0f, 10.0f, 50.0f}) {
        const float cut = pose_distance_mm(lm, a, b, bound);
        if (exact <= bound) {
          EXPECT_EQ(cut, exact) << name << " trial " << trial << " bound " << bound;
          ++below;
        } else {
          EXPECT_GT(cut, bound) << name << " trial " << trial << " bound " << bound;
          ++beyond;
        }
      }
    }
    EXPECT_GT(below, 200) << name;
    EXPECT_GT(beyond, 200) << name;
  }
}

TEST(RidgeIcp, ConvergesFromThePapersRanges) {
  OnePipe s = one_pipe("sbend", 4);
  const PipeModel& model = preset_model("sbend");
  Locator loc(model, s.cfg, s.scene.camera.intrinsics);
  const LocateOutput& out = loc.locate(s.scene.depth_mm, s.scene.camera);
  ASSERT_GE(out.traces.size(), 1u);
  const CandidateTrace& t = out.traces[0];
  ASSERT_GE(t.ridge_count, 10);
  const Pose truth = s.scene.model_to_world[0];
  const Eigen::Vector3d c = truth * model.centroid.cast<double>();
  const Eigen::Vector3d axis(t.axis.axis.x(), t.axis.axis.y(), 0);
  IcpBuffers buf;
  reserve_icp(&buf, loc.locator_model(), 2000, float(s.cfg.ridge_cell_mm));
  const Eigen::Vector3f* ridge = &loc.ridge_points()[std::size_t(t.ridge_begin)];
  // The region's points, for the refinement.
  std::vector<Eigen::Vector3f> region;
  const auto& r = loc.regions().candidates[0];
  for (int k = r.cells_begin; k < r.cells_end; ++k) {
    const int cell = loc.regions().region_cells[std::size_t(k)];
    region.push_back(loc.zbuffer().point(cell % loc.zbuffer().z.width, cell / loc.zbuffer().z.width));
  }
  for (const double deg : {-70.0, -35.0, 0.0, 35.0, 70.0}) {
    for (const double shift : {-30.0, 30.0}) {
      const Eigen::AngleAxisd turn(deg * M_PI / 180, axis);
      Pose start = truth;
      start.linear() = turn * truth.linear();
      start.translation() = c + turn * (truth.translation() - c) + axis * shift;
      const RidgeFit fit = ridge_icp(loc.locator_model(), start, ridge, t.ridge_count, t.axis.axis, s.cfg,
                                     s.cfg.icp_max_iterations * 2, &buf);
      const RefineResult ref =
          refine_on_surface(loc.locator_model(), fit.pose, region.data(), int(region.size()), s.cfg);
      EXPECT_LT(pose_error(model, ref.pose, truth), 5.0) << deg << " deg, " << shift << " mm";
    }
  }
}

// Beyond the paper: a start placed beside the pipe (one leg of the U onto the other) or along it
// is slid back over the observed ridge before ICP. The observed ridge here is a start's own ridge
// placed by a known axis frame; the slide must find that frame again from shifted ones.
TEST(StartSlide, BringsAnOffsetStartBackOverTheObservedRidge) {
  const PipeModel& model = preset_model("u");
  LocateConfig cfg;
  const LocatorModel lm = prepare_locator_model(model, 8.0f, cfg);
  const StartSet starts = prepare_starts(lm, cfg);
  ASSERT_EQ(starts.size(), 2 * cfg.initial_rotations * 6);  // 2 directions x 6 turns x 6 yaws (30 deg)
  ASSERT_GT(lm.slide_across_mm, 2 * lm.tube_d_mm);          // a U is wider than two tubes
  IcpBuffers buf;
  reserve_icp(&buf, lm, 2000, float(cfg.ridge_cell_mm));
  const float d = lm.tube_d_mm;
  Pose truth_frame = Pose::Identity();
  truth_frame.linear() = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  truth_frame.translation() = Eigen::Vector3d(120, -40, 900);
  const int s = 0;  // lying flat, not reversed, no yaw offset
  std::vector<Eigen::Vector3f> observed, in_axis;
  const Pose placed = truth_frame * starts.pose[s];
  for (int i = 0; i < starts.ridge_count(s); ++i)
    observed.push_back((placed * starts.ridge(s)[i].cast<double>()).cast<float>());
  ASSERT_GE(observed.size(), 10u);
  buf.observed_top.build(observed.data(), int(observed.size()), starts.cell_mm, d);
  const float widest = std::floor(lm.slide_across_mm / d) * d;  // the furthest step across it takes
  const Eigen::Vector3d along = truth_frame.linear().col(0), across = truth_frame.linear().col(1);
  for (const Eigen::Vector3d& offset :
       {Eigen::Vector3d(across * widest), Eigen::Vector3d(-across * 2 * d), Eigen::Vector3d(along * 2 * d),
        Eigen::Vector3d(-along * 2 * d + across * d)}) {
    Pose frame = truth_frame;
    frame.translation() += offset;  // the measured centre is off by `offset`
    in_axis.clear();
    for (const auto& p : observed) in_axis.push_back((frame.inverse() * p.cast<double>()).cast<float>());
    const SlidStart slid = slide_start(lm, starts, s, frame, in_axis.data(), int(in_axis.size()), cfg, &buf);
    EXPECT_LT((slid.pose.translation() - placed.translation()).norm(), 0.5 * d) << offset.transpose();
    EXPECT_LT(slid.cost_mm, 0.25f * d) << offset.transpose();
  }
}

TEST(StartSlide, TopDistanceIsTheHorizontalDistanceUpToItsCap) {
  TopDistance td;
  td.reserve(64);
  const Eigen::Vector3f pts[] = {{0, 0, 5}, {10, 0, 50}};
  td.build(pts, 2, 1.0f, 20.0f);
  EXPECT_NEAR(td.at(5, 0), 5.0f, 0.8f);  // between the two, heights aside
  EXPECT_NEAR(td.at(10, 6), 6.0f, 0.8f);
  EXPECT_FLOAT_EQ(td.at(0, 30), 20.0f);   // beyond the cap
  EXPECT_FLOAT_EQ(td.at(500, 0), 20.0f);  // outside the grid
}

TEST(StartSlide, SeenThroughCountsOnlyPointsAboveAReadingDeeperThanTheTolerance) {
  ZBuffer zb = synthetic_zbuffer(40, [](double i, double) { return i < 20 ? 0.0 : ZBuffer::kEmpty; });
  const Eigen::Vector3f pts[] = {{5, 5, 10},    // 10 mm over the floor: seen through
                                 {6, 5, 5},     // within the tolerance
                                 {7, 5, -3},    // under the surface: hidden, not seen through
                                 {30, 5, 10}};  // no reading there: says nothing
  EXPECT_FLOAT_EQ(seen_through_share(zb, pts, 4, 7.0f), 0.25f);
}

SimulatedScene pile_of(const PipeModel& model, int pipes, unsigned seed) {
  std::mt19937 rng(seed);
  SceneParams p;
  p.pile.pipes = pipes;
  return simulate_scene(model, p, rng);
}

// Verification skips the faces of a closed model turned away from the camera: the depth drawn
// must be the same as with every face, at poses seen from above, from the side and tilted.
TEST(Verification, SkippingBackFacesOfAClosedModelDrawsTheSameDepth) {
  const PipeModel& model = preset_model("u");
  const Mesh welded = weld_vertices(model.mesh, model.tube_diameter_mm / 8);
  const Winding winding = closed_winding(model.mesh);
  ASSERT_EQ(winding, Winding::outward);
  Intrinsics k;
  k.width = 640, k.height = 480, k.fx = k.fy = 570, k.cx = 320, k.cy = 240;
  Image<float> all(k.width, k.height, 0.0f), front(k.width, k.height, 0.0f);
  ProjectedMesh projected;
  projected.reserve(welded);
  int drawn = 0;
  for (const Eigen::Vector3d& turn :
       {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1.2, 0.3, 0), Eigen::Vector3d(0.4, 1.5, 0.7)}) {
    Pose pose = Pose::Identity();
    if (turn.norm() > 0) pose.linear() = Eigen::AngleAxisd(turn.norm(), turn.normalized()).toRotationMatrix();
    pose.translation() = Eigen::Vector3d(20, -10, 900);
    const PixelBox a = render_depth_in_box(welded, pose, k, &all, &projected);
    const PixelBox b = render_depth_in_box(welded, pose, k, &front, &projected, winding);
    ASSERT_FALSE(a.empty());
    EXPECT_EQ(a.x0, b.x0);
    EXPECT_EQ(a.y1, b.y1);
    int differ = 0;
    for (int y = a.y0; y <= a.y1; ++y)
      for (int x = a.x0; x <= a.x1; ++x) {
        drawn += all.at(x, y) > 0;
        differ += std::abs(all.at(x, y) - front.at(x, y)) > 1e-3f;
      }
    EXPECT_EQ(differ, 0) << turn.transpose();
  }
  EXPECT_GT(drawn, 3000);
}

// The locator builds its Z-buffer and fills its holes in row bands on its threads; one band on
// one thread must give the same buffer, cell for cell.
TEST(ZBufferBuild, RowBandsOnThreadsGiveTheSameBufferAsOneBand) {
  const PipeModel& model = preset_model("sbend");
  const SimulatedScene s = pile_of(model, 12, 5);
  LocateConfig cfg;
  cfg.threads = 2;
  Locator loc(model, cfg, s.camera.intrinsics);
  loc.locate(s.depth_mm, s.camera);
  ZBuffer one;
  reserve_zbuffer(&one, cfg.zbuffer_max_side_mm, cfg.zbuffer_pixel_mm);
  ZBufferPoints pts;
  reserve_zbuffer_points(&pts, s.depth_mm.width, s.depth_mm.height, 1);
  HoleList holes;
  holes.reserve(one);
  EXPECT_GT(build_zbuffer(s.depth_mm, s.camera.intrinsics, bin_to_camera(s.camera), &pts, &one), 0);
  const LocateConfig& used = loc.config();  // the derived thresholds in effect for that frame
  const int passes = int(std::lround(used.hole_fill_mm / 2 / used.zbuffer_pixel_mm));
  ASSERT_GT(passes, 0);
  fill_small_holes(&one, passes, float(used.continuity_step_max_mm), &holes);
  const ZBuffer& banded = loc.zbuffer();
  ASSERT_EQ(one.width, banded.width);
  ASSERT_EQ(one.height, banded.height);
  EXPECT_EQ(one.origin_x_mm, banded.origin_x_mm);
  EXPECT_EQ(one.origin_y_mm, banded.origin_y_mm);
  int valid = 0, differ = 0;
  for (int j = 0; j < one.height; ++j)
    for (int i = 0; i < one.width; ++i) {
      const float a = one.z.at(i, j), b = banded.z.at(i, j);
      valid += !std::isnan(a);
      differ += std::isnan(a) != std::isnan(b) || (!std::isnan(a) && a != b);
    }
  EXPECT_GT(valid, one.width * one.height / 2);
  EXPECT_EQ(differ, 0);
}

// For each pipe of the scene, how many of the given Z-buffer cells lie within tol_mm of its surface.
std::vector<int> pipe_votes(const Locator& loc, const SimulatedScene& s, const int* cells, int n,
                            float tol_mm) {
  std::vector<int> votes(s.model_to_world.size(), 0);
  const ZBuffer& zb = loc.zbuffer();
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d pt = zb.point(cells[k] % zb.z.width, cells[k] / zb.z.width).cast<double>();
    for (std::size_t g = 0; g < votes.size(); ++g) {
      const Eigen::Vector3f q = (s.model_to_world[g].inverse() * pt).cast<float>();
      const LocatorModel::Sample* smp = loc.locator_model().nearest_sample(q);
      votes[g] += smp && (smp->p - q).norm() < tol_mm;
    }
  }
  return votes;
}

// The pipe most of the cells voted for.
std::size_t most_voted(const std::vector<int>& votes) {
  return std::size_t(std::max_element(votes.begin(), votes.end()) - votes.begin());
}

TEST(Segmentation, CandidateCoresLieOnTopPipes) {
  const PipeModel& model = preset_model("u");
  const SimulatedScene s = pile_of(model, 12, 21);
  LocateConfig cfg;
  Locator loc(model, cfg, s.camera.intrinsics);
  loc.locate(s.depth_mm, s.camera);
  const auto& rb = loc.regions();
  ASSERT_GE(rb.candidates.size(), 1u);
  // Each core cell is attributed to the pipe whose surface it lies on; a candidate's core must be
  // mostly one pipe, and that pipe little covered by others.
  int on_top = 0;
  for (const auto& cand : rb.candidates) {
    const std::vector<int> votes = pipe_votes(loc, s, &rb.core_cells[std::size_t(cand.core_begin)],
                                              cand.core_end - cand.core_begin, 3.0f);
    const std::size_t best = most_voted(votes);
    const int core = cand.core_end - cand.core_begin;
    EXPECT_GT(votes[best], core * 7 / 10);
    on_top += s.info[best].occ_by_pipes <= 0.15;
  }
  EXPECT_GE(on_top * 10, int(rb.candidates.size()) * 7);
}

// A pipe whose top strip falls into several cores grows several regions; one lying mostly in an
// earlier candidate's region is not tried again. Over simulated piles, each candidate region is
// attributed to the pipe most of its cells lie on: the rule must leave fewer pipes tried twice and
// every pipe tried that was tried without it.
TEST(Segmentation, APipeBrokenIntoPiecesIsTriedOnce) {
  const PipeModel& model = preset_model("sbend");
  LocateConfig loose;
  loose.region_max_claimed_share = 1;  // every region grown is a candidate
  const LocateConfig cfg;
  int repeats_loose = 0, repeats = 0, pipes_loose = 0, pipes = 0, lost = 0;
  for (unsigned seed = 40; seed < 44; ++seed) {
    const SimulatedScene s = pile_of(model, 14, seed);
    const auto tried = [&](const LocateConfig& c) {
      Locator loc(model, c, s.camera.intrinsics);
      loc.locate(s.depth_mm, s.camera);
      const auto& rb = loc.regions();
      std::vector<int> per_pipe(s.model_to_world.size(), 0);
      for (const auto& cand : rb.candidates) {
        const std::vector<int> votes = pipe_votes(loc, s, &rb.region_cells[std::size_t(cand.cells_begin)],
                                                  cand.cells_end - cand.cells_begin, 3.0f);
        ++per_pipe[most_voted(votes)];
      }
      return per_pipe;
    };
    const std::vector<int> a = tried(loose), b = tried(cfg);
    for (std::size_t g = 0; g < a.size(); ++g) {
      repeats_loose += std::max(0, a[g] - 1), repeats += std::max(0, b[g] - 1);
      pipes_loose += a[g] > 0, pipes += b[g] > 0, lost += a[g] > 0 && b[g] == 0;
    }
  }
  std::printf("pipes tried %d / %d, extra tries of a pipe %d / %d (every region / the rule), lost %d\n",
              pipes_loose, pipes, repeats_loose, repeats, lost);
  EXPECT_GT(repeats_loose, 0) << "the piles should hold pipes whose strip falls into pieces";
  EXPECT_LT(repeats, repeats_loose);
  EXPECT_EQ(lost, 0);
}

// Beyond the paper: two straight pipes lying side by side on the floor, touching, one half a
// length along the other, seen through the sensor model. Plane fits straddling the V between them
// give upward normals, so the paper's cores join the two tops into one core too long to be a pipe,
// and neither is tried. Split along the valley, each pipe gets a core of its own in some frames
// (the valley is not always found whole), and no piece of the floor becomes a candidate.
TEST(Segmentation, TouchingPipesSideBySideGetACoreEach) {
  PipeSpec spec;
  spec.diameter_mm = 20;
  spec.segments = parse_centreline("S200");
  const PipeModel model = derive_pipe_model(make_pipe(spec), "straight");
  const double r = 10;
  const Eigen::Matrix3d axes = principal_axes(model.surface.points, model.centroid);
  Eigen::Matrix3d to_world;  // the model's long axis along world X
  to_world.row(0) = axes.col(2).transpose();
  to_world.row(1) = axes.col(1).transpose();
  to_world.row(2) = to_world.row(0).cross(to_world.row(1));
  const auto lying_at = [&](double x, double y) {
    Pose p = Pose::Identity();
    p.linear() = to_world;
    p.translation() = Eigen::Vector3d(x, y, r + 0.5) - to_world * model.centroid.cast<double>();
    return p;
  };
  // Over several frames (camera placement and sensor noise drawn anew): in how many does each of
  // the two pipes get a candidate whose core lies mostly on it.
  LocateConfig paper;
  paper.core_valley_turn = 0;  // the paper's cores
  const LocateConfig cfg;
  constexpr int kFrames = 8;
  int both_paper = 0, both_split = 0, off_pipe = 0;
  for (int frame = 0; frame < kFrames; ++frame) {
    std::mt19937 rng(unsigned(100 + frame));
    SceneParams params;
    const SimulatedScene s =
        render_scene(model, {lying_at(-50, -r - 0.1), lying_at(50, r + 0.1)}, params, rng);
    const auto pipes_with_a_core = [&](const LocateConfig& c) {
      Locator loc(model, c, s.camera.intrinsics);
      loc.locate(s.depth_mm, s.camera);
      const auto& rb = loc.regions();
      bool on[2] = {false, false};
      for (const auto& cand : rb.candidates) {
        const std::vector<int> votes = pipe_votes(loc, s, &rb.core_cells[std::size_t(cand.core_begin)],
                                                  cand.core_end - cand.core_begin, 3.0f);
        const std::size_t best = most_voted(votes);
        if (votes[best] > (cand.core_end - cand.core_begin) * 7 / 10)
          on[best] = true;
        else
          ++off_pipe;
      }
      return int(on[0]) + int(on[1]);
    };
    both_paper += pipes_with_a_core(paper) == 2;
    both_split += pipes_with_a_core(cfg) == 2;
  }
  std::printf("frames with a core on each pipe: paper %d of %d, split %d of %d\n", both_paper, kFrames,
              both_split, kFrames);
  // Measured: the paper 0 of 8, split 4 of 8.
  EXPECT_LE(both_paper, kFrames / 4) << "the two tops should mostly join into a core too long";
  EXPECT_GE(both_split, both_paper + kFrames / 4);
  EXPECT_EQ(off_pipe, 0) << "a candidate core not on a pipe (the floor split into pieces)";
}

// Beyond the paper: growth held to about a diameter from the core keeps a region on its pipe; the
// paper's unlimited growth runs on over touching pipes, and such a region is dropped or mixed.
// Measured on piles: how many candidate regions, and the share of a region's cells that lie on the
// pipe most of them lie on.
double mean_region_purity(const PipeModel& model, const SimulatedScene& s, const LocateConfig& cfg,
                          int* regions) {
  Locator loc(model, cfg, s.camera.intrinsics);
  loc.locate(s.depth_mm, s.camera);
  const auto& rb = loc.regions();
  double sum = 0;
  for (const auto& cand : rb.candidates) {
    const std::vector<int> votes = pipe_votes(loc, s, &rb.region_cells[std::size_t(cand.cells_begin)],
                                              cand.cells_end - cand.cells_begin, 6.0f);
    sum += double(*std::max_element(votes.begin(), votes.end())) / double(cand.cells_end - cand.cells_begin);
  }
  *regions = int(rb.candidates.size());
  return rb.candidates.empty() ? 0 : sum / double(rb.candidates.size());
}

TEST(Segmentation, HeldGrowthKeepsRegionsOnTheirPipe) {
  const PipeModel& model = preset_model("sbend");
  LocateConfig held, unlimited;
  unlimited.region_max_reach_of_d = 100;
  double p_held = 0, p_unlimited = 0;
  int n_held = 0, n_unlimited = 0;
  for (const unsigned seed : {6u, 7u, 8u}) {
    const SimulatedScene s = pile_of(model, 20, seed);
    int h = 0, u = 0;
    p_held += mean_region_purity(model, s, held, &h) / 3;
    p_unlimited += mean_region_purity(model, s, unlimited, &u) / 3;
    n_held += h, n_unlimited += u;
  }
  // Measured: 25 regions of purity 0.80 held, against 20 of 0.77 unlimited (regions that spread
  // over touching pipes are dropped as leaks). Cells within 6 mm of a pipe's surface count as on
  // it; the rest are the sensor's noise, the floor and the pipe beneath.
  ASSERT_GE(n_held, 9);
  EXPECT_GT(p_held, 0.7);
  EXPECT_GE(p_held, p_unlimited);
  EXPECT_GT(n_held, n_unlimited);
}

TEST(Locator, EndToEndPickIsATopPipe) {
  const PipeModel& model = preset_model("sbend");
  const SimulatedScene s = pile_of(model, 10, 8);
  LocateConfig cfg;
  Locator loc(model, cfg, s.camera.intrinsics);
  const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
  const int pick = out.pick();
  ASSERT_GE(pick, 0);
  double best = 1e9;
  std::size_t g_best = 0;
  for (std::size_t g = 0; g < s.model_to_world.size(); ++g) {
    const double e = pose_error(model, out.estimates[std::size_t(pick)].model_to_cam, s.model_to_cam(g));
    if (e < best) best = e, g_best = g;
  }
  EXPECT_LT(best, 5.0);
  EXPECT_LE(s.info[g_best].occ_by_pipes, 0.15);
}

// A near-symmetric pipe (a half-turn swaps its ends and lands its surface within D/4 of itself):
// where a pile shows only the common surface, the image cannot tell the pose from its twin. No
// pose handed out as pickable may be the twin of a pipe instead of the pipe (106 mm off at the
// ends): either the right one is taken or the estimate loses its confidence. Without the twin
// judged, 13 of 40 pickable poses on these 12 piles were twins; with it, 1 of 7 (a twin the image
// confirms better than the pipe's own pose, 0.92 against 0.75 agreement).
TEST(Locator, NoPickablePoseIsTheTwinOfANearSymmetricPipe) {
  PipeSpec spec;
  spec.diameter_mm = 16;
  spec.segments = parse_centreline("S30,B120r45t90,B90r45t90,S30");
  const PipeModel model = derive_pipe_model(make_pipe(spec), "coil");
  ASSERT_EQ(model.near_symmetries.size(), 1u);
  const Pose& twin = model.near_symmetries[0];
  LocateConfig cfg;
  int pickable = 0, twins_picked = 0;
  for (unsigned seed = 1; seed <= 12; ++seed) {
    const SimulatedScene s = pile_of(model, 20, seed);
    Locator loc(model, cfg, s.camera.intrinsics);
    for (const PipeEstimate& e : loc.locate(s.depth_mm, s.camera).estimates) {
      if (!e.pickable) continue;
      ++pickable;
      double at_truth = 1e9, at_twin = 1e9;
      for (std::size_t g = 0; g < s.model_to_world.size(); ++g) {
        at_truth = std::min(at_truth, pose_error(model, e.model_to_cam, s.model_to_cam(g)));
        at_twin = std::min(at_twin, pose_error(model, e.model_to_cam, s.model_to_cam(g) * twin));
      }
      twins_picked += at_truth > 10 && at_twin < 5;
    }
  }
  EXPECT_GE(pickable, 1);
  EXPECT_LE(5 * twins_picked, pickable) << twins_picked << " of " << pickable << " pickable poses are twins";
}

TEST(Locator, EmptyAndInvalidFramesGiveNothingAndDoNotCrash) {
  const PipeModel& model = preset_model("u");
  LocateConfig cfg;
  Intrinsics k;
  Locator loc(model, cfg, k);
  CameraInfo cam;
  cam.intrinsics = k;
  Image<float> depth(k.width, k.height, 0.0f);
  EXPECT_TRUE(loc.locate(depth, cam).estimates.empty());
  depth.fill(std::nanf(""));
  EXPECT_TRUE(loc.locate(depth, cam).estimates.empty());
  depth.fill(1000.0f);  // a flat floor: upward everywhere, but no pipe
  EXPECT_TRUE(loc.locate(depth, cam).estimates.empty());
}

TEST(Config, ErrorsNameFileKeyAndExpectation) {
  test::TempDir dir;
  const auto error_of = [&](const std::string& text) {
    test::write_text(dir.file("c.toml"), text);
    try {
      load_config(dir.file("c.toml"));
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  std::string msg = error_of("[locate]\nupward_normal_max_degrees = 20\n");
  EXPECT_NE(msg.find("c.toml"), std::string::npos) << msg;
  EXPECT_NE(msg.find("locate.upward_normal_max_degrees: unknown key"), std::string::npos) << msg;
  msg = error_of("[locate]\nmax_candidates = 2.5\n");
  EXPECT_NE(msg.find("expected an integer"), std::string::npos) << msg;
  msg = error_of("[locate]\nverify_min_agreement = 3\n");
  EXPECT_NE(msg.find("in [0, 1]"), std::string::npos) << msg;
  msg = error_of("[locate]\nscan_step_deg = \"five\"\n");
  EXPECT_NE(msg.find("locate.scan_step_deg"), std::string::npos) << msg;
  msg = error_of("[locate\n");
  EXPECT_NE(msg.find("line 1"), std::string::npos) << msg;
  msg = error_of("[camera]\nfx = 1\n");
  EXPECT_NE(msg.find("unknown section"), std::string::npos) << msg;
  EXPECT_EQ(error_of("[model]\nstl = \"pipe.stl\"\n[locate]\nscan_step_deg = 2.5\nmax_candidates = 8\n"), "");
  const AppConfig cfg = load_config(dir.file("c.toml"));
  EXPECT_DOUBLE_EQ(cfg.locate.scan_step_deg, 2.5);
  EXPECT_EQ(cfg.locate.max_candidates, 8);
  EXPECT_EQ(cfg.model_path, dir.file("pipe.stl"));
}

// The pool's threads spin briefly between runs, then block: every run still runs each of its
// tasks exactly once and returns only when all are done, whether the runs follow one another at
// once (spinning) or after a pause longer than the spin (blocked and woken).
TEST(WorkerPool, EveryTaskOnceWhetherRunsFollowAtOnceOrAfterAPause) {
  for (const int threads : {1, 2, 3}) {
    WorkerPool pool(threads);
    struct Run {
      std::atomic<int> count[8];
      std::atomic<int> slow_done{0};
    } run;
    const auto task = [](void* ctx, int t, int) {
      Run& r = *static_cast<Run*>(ctx);
      if (t % 3 == 0) {  // some tasks take a while, so that run() has to wait for them
        const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(50);
        while (std::chrono::steady_clock::now() < until) {
        }
        r.slow_done.fetch_add(1);
      }
      r.count[t].fetch_add(1);
    };
    for (int rep = 0; rep < 300; ++rep) {
      const int tasks = rep % 9;  // 0 to 8 tasks (0: a run with nothing to do)
      for (auto& c : run.count) c = 0;
      run.slow_done = 0;
      pool.run(tasks, task, &run);
      for (int t = 0; t < 8; ++t) ASSERT_EQ(run.count[t].load(), t < tasks ? 1 : 0) << threads << " " << rep;
      ASSERT_EQ(run.slow_done.load(), (tasks + 2) / 3);
      if (rep % 50 == 49) std::this_thread::sleep_for(std::chrono::milliseconds(2));  // past the spin
    }
  }
}

}  // namespace
}  // namespace pipeloc
