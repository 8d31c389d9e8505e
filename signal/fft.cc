#include "jointlab/signal/fft.h"

#include <cassert>
#include <cstring>
#include <mutex>

#include <fftw3.h>

namespace jointlab::signal {

namespace {
// FFTW's planner is not thread-safe; plan creation and destruction are
// serialised here (execution with new-array functions is thread-safe).
std::mutex& planner_mutex() {
  static std::mutex m;
  return m;
}
}  // namespace

struct Fft::Impl {
  Eigen::Index n = 0;
  double* real_in = nullptr;
  fftw_complex* half_out = nullptr;
  fftw_complex* full_in = nullptr;
  fftw_complex* full_out = nullptr;
  fftw_plan r2c = nullptr;
  fftw_plan c2c_backward = nullptr;
  fftw_plan c2r = nullptr;

  explicit Impl(Eigen::Index size) : n(size) {
    std::lock_guard<std::mutex> lock(planner_mutex());
    real_in = fftw_alloc_real(n);
    half_out = fftw_alloc_complex(n / 2 + 1);
    full_in = fftw_alloc_complex(n);
    full_out = fftw_alloc_complex(n);
  }
  ~Impl() {
    std::lock_guard<std::mutex> lock(planner_mutex());
    for (fftw_plan p : {r2c, c2c_backward, c2r})
      if (p) fftw_destroy_plan(p);
    fftw_free(real_in);
    fftw_free(half_out);
    fftw_free(full_in);
    fftw_free(full_out);
  }
  // Each plan is made on its first use: most sizes need one or two of the three, and
  // planning costs more than a transform.
  fftw_plan forward_plan() {
    if (!r2c) {
      std::lock_guard<std::mutex> lock(planner_mutex());
      r2c = fftw_plan_dft_r2c_1d(static_cast<int>(n), real_in, half_out, FFTW_ESTIMATE);
    }
    return r2c;
  }
  fftw_plan complex_plan() {
    if (!c2c_backward) {
      std::lock_guard<std::mutex> lock(planner_mutex());
      c2c_backward =
          fftw_plan_dft_1d(static_cast<int>(n), full_in, full_out, FFTW_BACKWARD, FFTW_ESTIMATE);
    }
    return c2c_backward;
  }
  // c2r overwrites its input: it reads full_in (n/2 + 1 values) and writes real_in.
  fftw_plan real_plan() {
    if (!c2r) {
      std::lock_guard<std::mutex> lock(planner_mutex());
      c2r = fftw_plan_dft_c2r_1d(static_cast<int>(n), full_in, real_in, FFTW_ESTIMATE);
    }
    return c2r;
  }
};

Fft::Fft(Eigen::Index n) : impl_(std::make_unique<Impl>(n)) { assert(n >= 2); }
Fft::~Fft() = default;
Fft::Fft(Fft&&) noexcept = default;
Fft& Fft::operator=(Fft&&) noexcept = default;

Eigen::Index Fft::size() const { return impl_->n; }

Eigen::VectorXcd Fft::forward(const Eigen::Ref<const Eigen::VectorXd>& x) {
  const Eigen::Index n = impl_->n;
  assert(x.size() <= n);
  std::memset(impl_->real_in, 0, sizeof(double) * n);
  for (Eigen::Index j = 0; j < x.size(); ++j) impl_->real_in[j] = x(j);
  fftw_execute(impl_->forward_plan());
  Eigen::VectorXcd out(n / 2 + 1);
  for (Eigen::Index k = 0; k <= n / 2; ++k) {
    out(k) = {impl_->half_out[k][0], impl_->half_out[k][1]};
  }
  return out;
}

Eigen::VectorXcd Fft::inverse_complex(const Eigen::Ref<const Eigen::VectorXcd>& spectrum) {
  const Eigen::Index n = impl_->n;
  assert(spectrum.size() == n);
  for (Eigen::Index k = 0; k < n; ++k) {
    impl_->full_in[k][0] = spectrum(k).real();
    impl_->full_in[k][1] = spectrum(k).imag();
  }
  fftw_execute(impl_->complex_plan());
  Eigen::VectorXcd out(n);
  const double scale = 1.0 / static_cast<double>(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    out(j) = {impl_->full_out[j][0] * scale, impl_->full_out[j][1] * scale};
  }
  return out;
}

std::complex<double>* Fft::complex_input() {
  impl_->complex_plan();  // planned before the input is filled
  std::memset(static_cast<void*>(impl_->full_in), 0, sizeof(fftw_complex) * impl_->n);
  // fftw_complex is double[2], laid out as std::complex<double>.
  return reinterpret_cast<std::complex<double>*>(impl_->full_in);
}

Eigen::VectorXcd Fft::inverse_complex_head(Eigen::Index count) {
  assert(count >= 0 && count <= impl_->n);
  fftw_execute(impl_->complex_plan());
  Eigen::VectorXcd out(count);
  const double scale = 1.0 / static_cast<double>(impl_->n);
  for (Eigen::Index j = 0; j < count; ++j) {
    out(j) = {impl_->full_out[j][0] * scale, impl_->full_out[j][1] * scale};
  }
  return out;
}

Eigen::VectorXd Fft::inverse_real(const Eigen::Ref<const Eigen::VectorXcd>& half_spectrum) {
  const Eigen::Index n = impl_->n;
  assert(half_spectrum.size() == n / 2 + 1);
  for (Eigen::Index k = 0; k <= n / 2; ++k) {
    impl_->full_in[k][0] = half_spectrum(k).real();
    impl_->full_in[k][1] = half_spectrum(k).imag();
  }
  fftw_execute(impl_->real_plan());
  Eigen::VectorXd out(n);
  const double scale = 1.0 / static_cast<double>(n);
  for (Eigen::Index j = 0; j < n; ++j) out(j) = impl_->real_in[j] * scale;
  return out;
}

Eigen::Index fast_size(Eigen::Index n) {
  for (Eigen::Index m = std::max<Eigen::Index>(n, 1);; ++m) {
    Eigen::Index r = m;
    for (Eigen::Index p : {2, 3, 5, 7}) {
      while (r % p == 0) r /= p;
    }
    if (r == 1) return m;
  }
}

}  // namespace jointlab::signal
