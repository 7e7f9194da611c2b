// II-A: normals of the Z-buffer.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>

#include "locate/locator.hpp"
#include "locate_fixtures.hpp"

namespace pipeloc {
namespace {

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

}  // namespace
}  // namespace pipeloc
