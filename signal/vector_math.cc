#include "jointlab/signal/vector_math.h"

#include <cassert>
#include <cmath>

// glibc's libmvec holds the vector versions of libm's functions that GCC's vectorizer calls
// (at most 4 ulp from the exact result). The vectorizer reaches them only under -ffast-math,
// which would let it reorder every other sum of the program, so they are called here by
// their vector-ABI names: 'd' four doubles in AVX2 registers where the processor has AVX2 and
// FMA, 'b' two in SSE2 registers (every x86-64) otherwise. Elsewhere std:: does the work.
#if defined(JOINTLAB_HAVE_LIBMVEC) && defined(__x86_64__)
#define JOINTLAB_LIBMVEC 1
#include <immintrin.h>

extern "C" {
__m128d _ZGVbN2vv_atan2(__m128d, __m128d);
__m128d _ZGVbN2v_exp(__m128d);
__m128d _ZGVbN2v_log(__m128d);
__m128d _ZGVbN2v_sin(__m128d);
__m128d _ZGVbN2v_cos(__m128d);
__m128d _ZGVbN2v_erfc(__m128d);
}
#pragma GCC push_options
#pragma GCC target("avx2,fma")
extern "C" {
__m256d _ZGVdN4vv_atan2(__m256d, __m256d);
__m256d _ZGVdN4v_exp(__m256d);
__m256d _ZGVdN4v_log(__m256d);
__m256d _ZGVdN4v_sin(__m256d);
__m256d _ZGVdN4v_cos(__m256d);
__m256d _ZGVdN4v_erfc(__m256d);
}
#pragma GCC pop_options
#endif

namespace jointlab::signal {

namespace {

#ifdef JOINTLAB_LIBMVEC

bool has_avx2() {
  static const bool yes = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return yes;
}

// Each function's two vector versions: F::four on AVX2 registers, F::two on SSE2 ones; y is
// the second argument of a two-argument function (ignored by the others).
#define JOINTLAB_VECTOR_FUNCTION(F, four, two)                                    \
  struct F {                                                                      \
    __attribute__((target("avx2,fma"))) static __m256d f4(__m256d x, __m256d y) { \
      static_cast<void>(y);                                                       \
      return four;                                                                \
    }                                                                             \
    static __m128d f2(__m128d x, __m128d y) {                                     \
      static_cast<void>(y);                                                       \
      return two;                                                                 \
    }                                                                             \
  }
JOINTLAB_VECTOR_FUNCTION(Atan2, _ZGVdN4vv_atan2(x, y), _ZGVbN2vv_atan2(x, y));
JOINTLAB_VECTOR_FUNCTION(Exp, _ZGVdN4v_exp(x), _ZGVbN2v_exp(x));
JOINTLAB_VECTOR_FUNCTION(Log, _ZGVdN4v_log(x), _ZGVbN2v_log(x));
JOINTLAB_VECTOR_FUNCTION(Sin, _ZGVdN4v_sin(x), _ZGVbN2v_sin(x));
JOINTLAB_VECTOR_FUNCTION(Cos, _ZGVdN4v_cos(x), _ZGVbN2v_cos(x));
JOINTLAB_VECTOR_FUNCTION(Erfc, _ZGVdN4v_erfc(x), _ZGVbN2v_erfc(x));
#undef JOINTLAB_VECTOR_FUNCTION

// F applied to n values (a the first argument, b the second or null), four at a time; the last
// few padded with `pad` (a value in the function's domain) and only the real ones stored.
template <typename F>
__attribute__((target("avx2,fma"))) void map4(const double* a, const double* b, double* out,
                                              Eigen::Index n, double pad) {
  Eigen::Index i = 0;
  for (; i + 4 <= n; i += 4) {
    const __m256d x = _mm256_loadu_pd(a + i);
    _mm256_storeu_pd(out + i, F::f4(x, b ? _mm256_loadu_pd(b + i) : x));
  }
  if (i == n) return;
  alignas(32) double xa[4] = {pad, pad, pad, pad}, ya[4] = {pad, pad, pad, pad}, r[4];
  for (Eigen::Index k = i; k < n; ++k) {
    xa[k - i] = a[k];
    ya[k - i] = b ? b[k] : a[k];
  }
  _mm256_store_pd(r, F::f4(_mm256_load_pd(xa), _mm256_load_pd(ya)));
  for (Eigen::Index k = i; k < n; ++k) out[k] = r[k - i];
}

template <typename F>
void map2(const double* a, const double* b, double* out, Eigen::Index n, double pad) {
  Eigen::Index i = 0;
  for (; i + 2 <= n; i += 2) {
    const __m128d x = _mm_loadu_pd(a + i);
    _mm_storeu_pd(out + i, F::f2(x, b ? _mm_loadu_pd(b + i) : x));
  }
  if (i == n) return;
  alignas(16) double r[2];
  _mm_store_pd(r, F::f2(_mm_set_pd(pad, a[i]), _mm_set_pd(pad, b ? b[i] : a[i])));
  out[i] = r[0];
}

template <typename F>
void map(const double* a, const double* b, double* out, Eigen::Index n, double pad) {
  if (has_avx2()) {
    map4<F>(a, b, out, n, pad);
  } else {
    map2<F>(a, b, out, n, pad);
  }
}

#endif

}  // namespace

void atan2_array(const Eigen::Ref<const Eigen::ArrayXd>& y,
                 const Eigen::Ref<const Eigen::ArrayXd>& x, Eigen::Ref<Eigen::ArrayXd> out) {
  assert(x.size() == y.size() && out.size() == y.size());
#ifdef JOINTLAB_LIBMVEC
  map<Atan2>(y.data(), x.data(), out.data(), y.size(), 1.0);
#else
  for (Eigen::Index i = 0; i < y.size(); ++i) out(i) = std::atan2(y(i), x(i));
#endif
}

void exp_array(const Eigen::Ref<const Eigen::ArrayXd>& x, Eigen::Ref<Eigen::ArrayXd> out) {
  assert(out.size() == x.size());
#ifdef JOINTLAB_LIBMVEC
  map<Exp>(x.data(), nullptr, out.data(), x.size(), 0.0);
#else
  out = x.exp();
#endif
}

void log_array(const Eigen::Ref<const Eigen::ArrayXd>& x, Eigen::Ref<Eigen::ArrayXd> out) {
  assert(out.size() == x.size());
#ifdef JOINTLAB_LIBMVEC
  map<Log>(x.data(), nullptr, out.data(), x.size(), 1.0);
#else
  out = x.log();
#endif
}

void sincos_array(const Eigen::Ref<const Eigen::ArrayXd>& x, Eigen::Ref<Eigen::ArrayXd> sin,
                  Eigen::Ref<Eigen::ArrayXd> cos) {
  assert(sin.size() == x.size() && cos.size() == x.size());
#ifdef JOINTLAB_LIBMVEC
  map<Sin>(x.data(), nullptr, sin.data(), x.size(), 0.0);
  map<Cos>(x.data(), nullptr, cos.data(), x.size(), 0.0);
#else
  sin = x.sin();
  cos = x.cos();
#endif
}

void erfc_array(const Eigen::Ref<const Eigen::ArrayXd>& x, Eigen::Ref<Eigen::ArrayXd> out) {
  assert(out.size() == x.size());
#ifdef JOINTLAB_LIBMVEC
  map<Erfc>(x.data(), nullptr, out.data(), x.size(), 0.0);
#else
  for (Eigen::Index i = 0; i < x.size(); ++i) out(i) = std::erfc(x(i));
#endif
}

}  // namespace jointlab::signal
