#pragma once
// Small fixed-size linear algebra for the per-frame solvers: no allocation,
// row-major std::arrays.
#include <array>
#include <cmath>

#include "core/camera_model.h"

namespace ceilpose {

// Rotation by the vector w (Rodrigues).
inline Mat3 exp_so3(const Vec3& w) {
  const double theta = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
  if (theta < 1e-12) return {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const double kx = w[0] / theta, ky = w[1] / theta, kz = w[2] / theta;
  const double c = std::cos(theta), s = std::sin(theta), v = 1.0 - c;
  return {kx * kx * v + c,      kx * ky * v - kz * s, kx * kz * v + ky * s,
          kx * ky * v + kz * s, ky * ky * v + c,      ky * kz * v - kx * s,
          kx * kz * v - ky * s, ky * kz * v + kx * s, kz * kz * v + c};
}

// Cholesky solve of the active block of a symmetric positive definite N×N
// system; inactive unknowns get 0. False when the block is not SPD.
template <int N>
bool solve_spd(const std::array<double, N * N>& a, const std::array<bool, N>& active,
               const std::array<double, N>& b, std::array<double, N>* x) {
  // Factored on the active block alone: the fits free 4-7 of their 10
  // unknowns, and an inactive one's zeroed row would only subtract zeros.
  std::array<int, N> idx{};
  int m = 0;
  for (int i = 0; i < N; ++i)
    if (active[i]) idx[m++] = i;
  std::array<double, N * N> l{};
  std::array<double, N> y{};
  for (int j = 0; j < m; ++j) {
    double d = a[idx[j] * N + idx[j]];
    for (int k = 0; k < j; ++k) d -= l[j * N + k] * l[j * N + k];
    if (!(d > 0.0)) return false;
    d = std::sqrt(d);
    l[j * N + j] = d;
    for (int i = j + 1; i < m; ++i) {
      double s = a[idx[i] * N + idx[j]];
      for (int k = 0; k < j; ++k) s -= l[i * N + k] * l[j * N + k];
      l[i * N + j] = s / d;
    }
  }
  for (int i = 0; i < m; ++i) {
    double s = b[idx[i]];
    for (int k = 0; k < i; ++k) s -= l[i * N + k] * y[k];
    y[i] = s / l[i * N + i];
  }
  for (int i = m - 1; i >= 0; --i) {
    double s = y[i];
    for (int k = i + 1; k < m; ++k) s -= l[k * N + i] * y[k];
    y[i] = s / l[i * N + i];
  }
  x->fill(0.0);
  for (int i = 0; i < m; ++i) (*x)[idx[i]] = y[i];
  return true;
}

// Inverse of a symmetric 3x3 matrix; false when singular.
inline bool invert3(const std::array<double, 9>& m, std::array<double, 9>* inv) {
  const double c00 = m[4] * m[8] - m[5] * m[7];
  const double c01 = m[5] * m[6] - m[3] * m[8];
  const double c02 = m[3] * m[7] - m[4] * m[6];
  const double det = m[0] * c00 + m[1] * c01 + m[2] * c02;
  if (!(std::abs(det) > 1e-300)) return false;
  const double id = 1.0 / det;
  *inv = {c00 * id, (m[2] * m[7] - m[1] * m[8]) * id, (m[1] * m[5] - m[2] * m[4]) * id,
          c01 * id, (m[0] * m[8] - m[2] * m[6]) * id, (m[2] * m[3] - m[0] * m[5]) * id,
          c02 * id, (m[1] * m[6] - m[0] * m[7]) * id, (m[0] * m[4] - m[1] * m[3]) * id};
  return true;
}

// y^T m y for a 3x3 m (row-major).
inline double quadratic_form3(const std::array<double, 9>& m, const std::array<double, 3>& y) {
  double sum = 0.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) sum += y[i] * m[i * 3 + j] * y[j];
  return sum;
}

}  // namespace ceilpose
