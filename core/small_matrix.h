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
bool solve_spd(std::array<double, N * N> a, const std::array<bool, N>& active,
               std::array<double, N> b, std::array<double, N>* x) {
  for (int i = 0; i < N; ++i) {
    if (active[i]) continue;
    for (int j = 0; j < N; ++j) a[i * N + j] = a[j * N + i] = 0.0;
    a[i * N + i] = 1.0;
    b[i] = 0.0;
  }
  for (int j = 0; j < N; ++j) {
    double d = a[j * N + j];
    for (int k = 0; k < j; ++k) d -= a[j * N + k] * a[j * N + k];
    if (!(d > 0.0)) return false;
    d = std::sqrt(d);
    a[j * N + j] = d;
    for (int i = j + 1; i < N; ++i) {
      double s = a[i * N + j];
      for (int k = 0; k < j; ++k) s -= a[i * N + k] * a[j * N + k];
      a[i * N + j] = s / d;
    }
  }
  for (int i = 0; i < N; ++i) {
    double s = b[i];
    for (int k = 0; k < i; ++k) s -= a[i * N + k] * b[k];
    b[i] = s / a[i * N + i];
  }
  for (int i = N - 1; i >= 0; --i) {
    double s = b[i];
    for (int k = i + 1; k < N; ++k) s -= a[k * N + i] * b[k];
    b[i] = s / a[i * N + i];
  }
  *x = b;
  return true;
}

}  // namespace ceilpose
