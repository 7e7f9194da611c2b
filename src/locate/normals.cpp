#include "locate/normals.hpp"

#include <emmintrin.h>

#include <algorithm>
#include <cmath>

namespace pipeloc {
namespace {

constexpr int kSums = 9;  // n, Si, Sj, Sii, Sij, Sjj, Sz, Siz, Sjz

// Adds (sign +1) or removes (-1) row j to the column sums, one array per sum, two cells at a time.
// An empty cell adds zeros, which leave every sum as it was; each term is the product, in the same
// order, that a cell at a time would add. An odd last cell goes as a pair whose second is empty
// and not stored.
void accumulate(const ZBuffer& zb, int j, double sign, double* const* c) {
  if (j < 0 || j >= zb.height) return;
  const float* row = &zb.z.at(0, j);
  const __m128d vs = _mm_set1_pd(sign), vj = _mm_set1_pd(j), sj = _mm_set1_pd(sign * j),
                sjj = _mm_set1_pd(sign * j * j);
  const __m128 one = _mm_set1_ps(1.0f);
  const auto pair = [&](int i, __m128 zf, bool both) {
    const auto add = [both](double* at, __m128d v) {
      if (both)
        _mm_storeu_pd(at, _mm_add_pd(_mm_loadu_pd(at), v));
      else
        _mm_store_sd(at, _mm_add_sd(_mm_load_sd(at), v));
    };
    const __m128 valid = _mm_cmpord_ps(zf, zf);
    const __m128d z = _mm_cvtps_pd(_mm_and_ps(valid, zf)), on = _mm_cvtps_pd(_mm_and_ps(valid, one));
    const __m128d vi = _mm_set_pd(i + 1, i), si = _mm_mul_pd(vs, vi);
    add(c[0] + i, _mm_mul_pd(vs, on)), add(c[1] + i, _mm_mul_pd(si, on)), add(c[2] + i, _mm_mul_pd(sj, on));
    add(c[3] + i, _mm_mul_pd(_mm_mul_pd(si, vi), on)), add(c[4] + i, _mm_mul_pd(_mm_mul_pd(si, vj), on));
    add(c[5] + i, _mm_mul_pd(sjj, on));
    add(c[6] + i, _mm_mul_pd(vs, z)), add(c[7] + i, _mm_mul_pd(si, z)), add(c[8] + i, _mm_mul_pd(sj, z));
  };
  int i = 0;
  for (; i + 2 <= zb.width; i += 2)
    pair(i, _mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(row + i))), true);
  if (i < zb.width) pair(i, _mm_setr_ps(row[i], ZBuffer::kEmpty, 0, 0), false);
}

// The plane fit of cells [i, i+4) of a row from their window sums: (-a, -b, 1) normalised (summed in
// the order Eigen's normalized() sums it), or zero where the cell is empty, the window holds fewer
// than min_n valid cells or the fit is degenerate. Four at a time, each lane as one cell alone.
void fit_four(double* const* win, const float* z_row, int i, double min_n, double pixel,
              Eigen::Vector3f* out) {
  __m128d mask_d[2];
  __m128 xy[2];
  for (int h = 0; h < 2; ++h) {
    const int at = i + 2 * h;
    const auto load = [&](int q) { return _mm_loadu_pd(win[q] + at); };
    const __m128d n = load(0), inv_n = _mm_div_pd(_mm_set1_pd(1.0), n);
    const __m128d mi = _mm_mul_pd(load(1), inv_n), mj = _mm_mul_pd(load(2), inv_n),
                  mz = _mm_mul_pd(load(6), inv_n);
    // Least squares in coordinates centred on the window's mean (well conditioned).
    const __m128d cii = _mm_sub_pd(_mm_mul_pd(load(3), inv_n), _mm_mul_pd(mi, mi));
    const __m128d cij = _mm_sub_pd(_mm_mul_pd(load(4), inv_n), _mm_mul_pd(mi, mj));
    const __m128d cjj = _mm_sub_pd(_mm_mul_pd(load(5), inv_n), _mm_mul_pd(mj, mj));
    const __m128d ciz = _mm_sub_pd(_mm_mul_pd(load(7), inv_n), _mm_mul_pd(mi, mz));
    const __m128d cjz = _mm_sub_pd(_mm_mul_pd(load(8), inv_n), _mm_mul_pd(mj, mz));
    const __m128d det = _mm_sub_pd(_mm_mul_pd(cii, cjj), _mm_mul_pd(cij, cij));
    const __m128d inv_det = _mm_div_pd(_mm_set1_pd(1.0), det);
    const __m128d a = _mm_mul_pd(_mm_sub_pd(_mm_mul_pd(ciz, cjj), _mm_mul_pd(cjz, cij)), inv_det);  // dz/di
    const __m128d b = _mm_mul_pd(_mm_sub_pd(_mm_mul_pd(cjz, cii), _mm_mul_pd(ciz, cij)), inv_det);  // dz/dj
    const __m128d minus = _mm_set1_pd(-0.0), p = _mm_set1_pd(pixel);
    const __m128 x = _mm_cvtpd_ps(_mm_div_pd(_mm_xor_pd(a, minus), p));
    const __m128 y = _mm_cvtpd_ps(_mm_div_pd(_mm_xor_pd(b, minus), p));
    xy[h] = _mm_unpacklo_ps(x, y);  // x0 y0 x1 y1
    mask_d[h] = _mm_and_pd(_mm_cmpge_pd(n, _mm_set1_pd(min_n)), _mm_cmpge_pd(det, _mm_set1_pd(1e-9)));
  }
  const __m128 x = _mm_shuffle_ps(xy[0], xy[1], _MM_SHUFFLE(2, 0, 2, 0));
  const __m128 y = _mm_shuffle_ps(xy[0], xy[1], _MM_SHUFFLE(3, 1, 3, 1));
  const __m128 z = _mm_loadu_ps(z_row + i);
  const __m128 fitted =
      _mm_and_ps(_mm_cmpord_ps(z, z),
                 _mm_shuffle_ps(_mm_castpd_ps(mask_d[0]), _mm_castpd_ps(mask_d[1]), _MM_SHUFFLE(2, 0, 2, 0)));
  const __m128 one = _mm_set1_ps(1.0f);
  const __m128 norm = _mm_sqrt_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(x, x), _mm_mul_ps(y, y)), one));
  alignas(16) float nx[4], ny[4], nz[4];
  _mm_store_ps(nx, _mm_and_ps(fitted, _mm_div_ps(x, norm)));
  _mm_store_ps(ny, _mm_and_ps(fitted, _mm_div_ps(y, norm)));
  _mm_store_ps(nz, _mm_and_ps(fitted, _mm_div_ps(one, norm)));
  for (int l = 0; l < 4; ++l) out[i + l] = Eigen::Vector3f(nx[l], ny[l], nz[l]);
}

// The last cells of a row (fewer than four) through fit_four, on copies padded with empty cells.
void fit_tail(double* const* win, const float* z_row, int i, int w, double min_n, double pixel,
              Eigen::Vector3f* out) {
  double pad[kSums][4] = {};
  double* pad_win[kSums];
  float pad_z[4] = {ZBuffer::kEmpty, ZBuffer::kEmpty, ZBuffer::kEmpty, ZBuffer::kEmpty};
  Eigen::Vector3f pad_out[4];
  for (int q = 0; q < kSums; ++q) {
    pad_win[q] = pad[q];
    for (int l = 0; i + l < w; ++l) pad[q][l] = win[q][i + l];
  }
  for (int l = 0; i + l < w; ++l) pad_z[l] = z_row[i + l];
  fit_four(pad_win, pad_z, 0, min_n, pixel, pad_out);
  for (int l = 0; i + l < w; ++l) out[i + l] = pad_out[l];
}

}  // namespace

void reserve_normals(NormalMap* nm, const ZBuffer& zb, int bands) {
  nm->n.resize(zb.z.width, zb.z.height, Eigen::Vector3f::Zero());
  nm->bands = std::max(1, bands);
  nm->sums.assign(std::size_t(2 * kSums) * zb.z.width * std::size_t(nm->bands), 0.0);
}

void compute_normals_rows(const ZBuffer& zb, int window, int min_valid, int j0, int j1, int band,
                          NormalMap* nm) {
  const int k = window / 2;
  const int w = zb.width;
  // This band's scratch: the column sums (rows j-k .. j+k of each column), then the window sums.
  double* col[kSums];
  double* win[kSums];
  double* scratch = nm->sums.data() + std::size_t(band) * 2 * kSums * zb.z.width;
  for (int q = 0; q < kSums; ++q)
    col[q] = scratch + std::size_t(q) * zb.z.width, win[q] = scratch + std::size_t(kSums + q) * zb.z.width;
  for (int q = 0; q < kSums; ++q) std::fill(col[q], col[q] + w, 0.0);
  for (int j = j0 - k - 1; j < j0 + k; ++j) accumulate(zb, j, 1, col);  // the loop drops row j0-k-1 first
  const double min_n = min_valid;
  for (int j = j0; j < j1; ++j) {
    accumulate(zb, j + k, 1, col);
    accumulate(zb, j - k - 1, -1, col);
    // Window sums, sliding along the row (the nine sums are independent chains).
    double s[kSums] = {0};
    for (int i = 0; i < k && i < w; ++i)
      for (int q = 0; q < kSums; ++q) s[q] += col[q][i];
    for (int i = 0; i < w; ++i) {
      if (i + k < w)
        for (int q = 0; q < kSums; ++q) s[q] += col[q][i + k];
      if (i - k - 1 >= 0)
        for (int q = 0; q < kSums; ++q) s[q] -= col[q][i - k - 1];
      for (int q = 0; q < kSums; ++q) win[q][i] = s[q];
    }
    const float* zr = &zb.z.at(0, j);
    Eigen::Vector3f* out = &nm->n.at(0, j);
    int i = 0;
    for (; i + 4 <= w; i += 4) fit_four(win, zr, i, min_n, zb.pixel_mm, out);
    if (i < w) fit_tail(win, zr, i, w, min_n, zb.pixel_mm, out);
  }
}

void compute_normals(const ZBuffer& zb, int window, int min_valid, NormalMap* nm) {
  compute_normals_rows(zb, window, min_valid, 0, zb.height, 0, nm);
}

}  // namespace pipeloc
