#include "locate/normals.hpp"

#include <Eigen/Dense>

namespace pipeloc {
namespace {

constexpr int kSums = 9;  // n, Si, Sj, Sii, Sij, Sjj, Sz, Siz, Sjz

void accumulate(const ZBuffer& zb, int j, double sign, double* column) {
  if (j < 0 || j >= zb.height) return;
  for (int i = 0; i < zb.width; ++i) {
    const float z = zb.z.at(i, j);
    if (std::isnan(z)) continue;
    double* c = column + kSums * i;
    c[0] += sign;
    c[1] += sign * i;
    c[2] += sign * j;
    c[3] += sign * i * i;
    c[4] += sign * i * j;
    c[5] += sign * j * j;
    c[6] += sign * z;
    c[7] += sign * i * z;
    c[8] += sign * j * z;
  }
}

}  // namespace

void reserve_normals(NormalMap* nm, const ZBuffer& zb, int bands) {
  nm->n.resize(zb.z.width, zb.z.height, Eigen::Vector3f::Zero());
  nm->column.assign(std::size_t(kSums) * zb.z.width * std::size_t(std::max(1, bands)), 0.0);
}

void compute_normals_rows(const ZBuffer& zb, int window, int min_valid, int j0, int j1, double* col,
                          NormalMap* nm) {
  const int k = window / 2;
  std::fill(col, col + std::size_t(kSums) * zb.width, 0.0);
  for (int j = j0 - k - 1; j < j0 + k; ++j) accumulate(zb, j, 1, col);  // the loop drops row j0-k-1 first
  for (int j = j0; j < j1; ++j) {
    // Column sums hold rows j-k .. j+k.
    accumulate(zb, j + k, 1, col);
    accumulate(zb, j - k - 1, -1, col);
    double s[kSums] = {0};
    for (int i = 0; i < k && i < zb.width; ++i)
      for (int q = 0; q < kSums; ++q) s[q] += col[kSums * i + q];
    for (int i = 0; i < zb.width; ++i) {
      if (i + k < zb.width)
        for (int q = 0; q < kSums; ++q) s[q] += col[kSums * (i + k) + q];
      if (i - k - 1 >= 0)
        for (int q = 0; q < kSums; ++q) s[q] -= col[kSums * (i - k - 1) + q];
      Eigen::Vector3f& out = nm->n.at(i, j);
      out.setZero();
      if (std::isnan(zb.z.at(i, j)) || s[0] < min_valid) continue;
      // Least squares in coordinates centred on the window's mean (well conditioned).
      const double inv_n = 1 / s[0], mi = s[1] * inv_n, mj = s[2] * inv_n, mz = s[6] * inv_n;
      const double cii = s[3] * inv_n - mi * mi, cij = s[4] * inv_n - mi * mj, cjj = s[5] * inv_n - mj * mj;
      const double ciz = s[7] * inv_n - mi * mz, cjz = s[8] * inv_n - mj * mz;
      const double det = cii * cjj - cij * cij;
      if (det < 1e-9) continue;
      const double inv_det = 1 / det;
      const double a = (ciz * cjj - cjz * cij) * inv_det;  // dz/di
      const double b = (cjz * cii - ciz * cij) * inv_det;  // dz/dj
      out = Eigen::Vector3f(float(-a / zb.pixel_mm), float(-b / zb.pixel_mm), 1.0f).normalized();
    }
  }
}

void compute_normals(const ZBuffer& zb, int window, int min_valid, NormalMap* nm) {
  compute_normals_rows(zb, window, min_valid, 0, zb.height, nm->column.data(), nm);
}

}  // namespace pipeloc
