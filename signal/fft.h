// Real discrete Fourier transforms through FFTW, with plans made once per size.
//
// Conventions (unscaled forward, scaled inverse, as numpy.fft):
//   X[k] = sum_{j=0}^{n-1} x[j] exp(-2 pi i j k / n),   k = 0 .. n/2   (one-sided)
//   x[j] = (1/n) sum_k X[k] exp(+2 pi i j k / n)
// Bin k is the frequency k fs / n. Inputs shorter than n are zero-padded.
// One Fft object owns its plans and work buffers: reuse it across calls of the
// same size; it is not shared between threads (make one per thread).
#pragma once

#include <complex>
#include <memory>

#include <Eigen/Core>

namespace jointlab::signal {

/// Plans and buffers for real-to-complex and complex-to-complex transforms of one size.
class Fft {
 public:
  /// Prepares transforms of length n (n >= 2).
  explicit Fft(Eigen::Index n);
  ~Fft();
  Fft(const Fft&) = delete;
  Fft& operator=(const Fft&) = delete;
  Fft(Fft&&) noexcept;
  Fft& operator=(Fft&&) noexcept;

  /// Transform length.
  Eigen::Index size() const;
  /// One-sided spectrum X[0..n/2] of real x (x.size() <= n; zero-padded to n).
  Eigen::VectorXcd forward(const Eigen::Ref<const Eigen::VectorXd>& x);
  /// Complex inverse of a full n-point spectrum, scaled by 1/n.
  Eigen::VectorXcd inverse_complex(const Eigen::Ref<const Eigen::VectorXcd>& spectrum);
  /// The complex inverse's input, n values set to zero, to be filled before
  /// inverse_complex_head() (no copy of a mostly zero spectrum).
  std::complex<double>* complex_input();
  /// The first `count` values of the complex inverse of complex_input()'s n values, scaled by
  /// 1/n (the same numbers as inverse_complex gives).
  Eigen::VectorXcd inverse_complex_head(Eigen::Index count);
  /// Real inverse of a one-sided spectrum X[0..n/2] (Hermitian symmetry implied), scaled by 1/n.
  Eigen::VectorXd inverse_real(const Eigen::Ref<const Eigen::VectorXcd>& half_spectrum);
  /// In place, for records too long to copy: `data` holds n / 2 + 1 complex values; its first
  /// n doubles, the real x (zero-padded by the caller), become the one-sided spectrum X[0..n/2]
  /// (the same numbers as forward(x) up to rounding).
  void forward_in_place(std::complex<double>* data);
  /// forward_in_place's result, faster: up to 2^17 points through a buffer of the size's own
  /// (an out-of-place transform and a copy back), so its rounding differs from the in-place
  /// transform's; forward_in_place itself above that.
  void forward_through_buffer(std::complex<double>* data);
  /// In place: the one-sided spectrum X[0..n/2] in `data` (n / 2 + 1 complex values) becomes
  /// its real inverse x[0..n), scaled by 1/n, in data's first n doubles.
  void inverse_real_in_place(std::complex<double>* data);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Smallest m >= n whose prime factors are 2, 3, 5 and 7 (sizes FFTW is fastest on).
Eigen::Index fast_size(Eigen::Index n);

}  // namespace jointlab::signal
