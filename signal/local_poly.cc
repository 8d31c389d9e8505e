#include "jointlab/signal/local_poly.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstring>

#include <Eigen/Dense>

namespace jointlab::signal {

namespace {

// (Vectors of W doubles: GCC takes vector_size from a template argument only this way.)
template <int W>
struct Lanes;
template <>
struct Lanes<2> {
  typedef double type __attribute__((vector_size(16)));
};
template <>
struct Lanes<4> {
  typedef double type __attribute__((vector_size(32)));
};

namespace sse2 {
#include "local_poly_kernel.inc"
}  // namespace sse2

// GCC only: clang (the fuzzing build) takes the SSE2 kernel.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define JOINTLAB_AVX2_KERNEL 1
#pragma GCC push_options
#pragma GCC target("avx2")  // no FMA: a fused multiply-add where the compiler chooses would
                            // give the pair and the quad of one series different bits
namespace avx2 {
#include "local_poly_kernel.inc"
}  // namespace avx2
#pragma GCC pop_options
#endif

// The kernel for this processor: four samples a step in AVX2's registers where it has them.
template <int K, int Q>
std::array<LocalFit, K> fit_local_series(const std::array<const Eigen::VectorXd*, K>& ys,
                                         double t_first, double dt, double centre,
                                         double half_width, double correlation, Eigen::Index stride,
                                         double offset) {
#ifdef JOINTLAB_AVX2_KERNEL
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (avx2) {
    return avx2::fit_kernel<K, Q, 4>(ys, t_first, dt, centre, half_width, correlation, stride,
                                     offset);
  }
#endif
  return sse2::fit_kernel<K, Q, 2>(ys, t_first, dt, centre, half_width, correlation, stride,
                                   offset);
}

// Runtime degree -> compile-time column count.
template <int K>
std::array<LocalFit, K> dispatch(const std::array<const Eigen::VectorXd*, K>& ys, double t_first,
                                 double dt, double centre, double half_width, int degree,
                                 double correlation, Eigen::Index stride, double offset) {
  // fit_local_series for Q = degree + 1 columns, degree 1 to 5.
  constexpr std::array fits{&fit_local_series<K, 2>, &fit_local_series<K, 3>,
                            &fit_local_series<K, 4>, &fit_local_series<K, 5>,
                            &fit_local_series<K, 6>};
  if (degree < 1 || degree > static_cast<int>(fits.size())) {
    assert(false && "degree must be 1 to 5");
    return {};
  }
  return fits[static_cast<size_t>(degree - 1)](ys, t_first, dt, centre, half_width, correlation,
                                               stride, offset);
}

}  // namespace

// The single series goes through the pair's kernel beside itself: each series' sums and
// solution are its own, so the numbers are those of a kernel for one series, and the kernel
// is instantiated for two and four series only (a one-series set took a third of this file's
// 42 s build, for a function `process` does not call).
LocalFit fit_local(const Eigen::Ref<const Eigen::VectorXd>& y, double t_first, double dt,
                   double centre, double half_width, int degree, double correlation,
                   Eigen::Index stride, double offset) {
  assert(std::abs(offset) <= 1.0);
  const Eigen::VectorXd copy = y;
  return dispatch<2>({&copy, &copy}, t_first, dt, centre, half_width, degree, correlation, stride,
                     offset)[0];
}

std::array<LocalFit, 2> fit_local_pair(const Eigen::VectorXd& y1, const Eigen::VectorXd& y2,
                                       double t_first, double dt, double centre, double half_width,
                                       int degree, double correlation, Eigen::Index stride,
                                       double offset) {
  assert(y1.size() == y2.size());
  assert(std::abs(offset) <= 1.0);
  return dispatch<2>({&y1, &y2}, t_first, dt, centre, half_width, degree, correlation, stride,
                     offset);
}

std::array<LocalFit, 4> fit_local_quad(const std::array<const Eigen::VectorXd*, 4>& ys,
                                       double t_first, double dt, double centre, double half_width,
                                       int degree, double correlation, Eigen::Index stride,
                                       double offset) {
  assert(std::all_of(ys.begin(), ys.end(),
                     [&](const Eigen::VectorXd* y) { return y->size() == ys[0]->size(); }));
  assert(std::abs(offset) <= 1.0);
  return dispatch<4>(ys, t_first, dt, centre, half_width, degree, correlation, stride, offset);
}

}  // namespace jointlab::signal
