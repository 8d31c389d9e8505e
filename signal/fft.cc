#include "jointlab/signal/fft.h"

#include <algorithm>
#include <cassert>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <new>
#include <utility>
#include <vector>

#include <fftw3.h>

namespace jointlab::signal {

namespace {
// FFTW's planner is not thread-safe; plan creation and destruction are
// serialised here (execution with new-array functions is thread-safe).
std::mutex& planner_mutex() {
  static std::mutex m;
  return m;
}

// In-place plans of more points than this are made for one transform and destroyed after it:
// FFTW's tables for a plan take about 8 bytes a point (a 4e7-point plan 350 MB), as much as
// the record they transform, and a kept pair would double a long record's peak memory.
constexpr Eigen::Index kLargestKeptPlan = Eigen::Index{1} << 22;

// Up to this many points forward_through_buffer transforms into a buffer of the size's own and
// copies the spectrum back: FFTW's in-place real transform (an FFTW_ESTIMATE plan) copies the
// data through buffers of its own, and the out-of-place one and the copy take about two
// thirds of its time at 6e4-7e4 points (measured: 300 -> 200 us). Above it the buffers, kept
// with the cache's sizes, would add to a long record's peak memory (at 2^20 points a 5e6-sample
// record's grew from 131 MB to 163 MB).
constexpr Eigen::Index kLargestBufferedForward = Eigen::Index{1} << 17;
}  // namespace

struct Fft::Impl {
  Eigen::Index n = 0;
  // Work buffers, each allocated on the first transform that needs it: a size used only in
  // place (a long record's spectrum, above kLargestBufferedForward) never holds a buffer of
  // its own.
  double* real_in = nullptr;
  fftw_complex* half_out = nullptr;
  fftw_complex* full_in = nullptr;
  fftw_complex* full_out = nullptr;
  fftw_plan r2c = nullptr;
  fftw_plan c2c_backward = nullptr;
  fftw_plan c2r = nullptr;
  // In-place plans and the alignment of the array they were made for (FFTW runs a plan on
  // another array only if it is aligned alike): the latest in these slots, earlier ones of
  // other alignments kept below (a record's buffers come aligned one way or another, and
  // making the plan again each time was a thirtieth of process's time).
  fftw_plan r2c_in_place = nullptr;
  fftw_plan c2r_in_place = nullptr;
  int r2c_alignment = -1, c2r_alignment = -1;
  std::vector<std::pair<int, fftw_plan>> r2c_other, c2r_other;
  // forward_through_buffer's plans (into half_out), one for each alignment of the input met.
  std::vector<std::pair<int, fftw_plan>> r2c_buffered;

  explicit Impl(Eigen::Index size) : n(size) {}
  ~Impl() {
    std::lock_guard<std::mutex> lock(planner_mutex());
    for (fftw_plan p : {r2c, c2c_backward, c2r, r2c_in_place, c2r_in_place})
      if (p) fftw_destroy_plan(p);
    for (const auto* other : {&r2c_other, &c2r_other, &r2c_buffered})
      for (const auto& [alignment, p] : *other) fftw_destroy_plan(p);
    std::free(real_in);
    std::free(half_out);
    std::free(full_in);
    std::free(full_out);
  }
  // FFTW aborts the program when an allocation of its own fails (planning a large size makes
  // tables of 8-10 bytes a point): before planning, 12 bytes a point are asked for and given
  // back, so that a lack of them is std::bad_alloc here, which callers can name. A best
  // effort: where the system promises memory it has not got (Linux overcommit), the probe
  // succeeds and FFTW may still abort when it touches its tables.
  // At least 8 MB whatever the size: a small plan made when the process is at its limit (a
  // 1e6-sample record under ulimit -v 140 MB, planning the gain correction's short transform)
  // aborted in FFTW's twiddle allocation, where the probe had been skipped below 2^16 points.
  void probe_planning_memory(size_t bytes_a_point = 12) const {
    constexpr size_t kHeadroom = size_t{8} << 20;
    void* volatile p =
        std::malloc(std::max(kHeadroom, bytes_a_point * static_cast<size_t>(n)));  // kept
    if (!p) throw std::bad_alloc();
    std::free(p);
  }
  // SIMD-aligned like fftw_malloc's, which aborts where this throws std::bad_alloc.
  template <typename T>
  static void allocate(T*& p, Eigen::Index count) {
    if (p) return;
    void* q = nullptr;
    if (posix_memalign(&q, 64, sizeof(T) * static_cast<size_t>(count)) != 0) throw std::bad_alloc();
    p = static_cast<T*>(q);
  }
  // Each plan is made on its first use: most sizes need one or two of the three, and
  // planning costs more than a transform.
  fftw_plan forward_plan() {
    if (!r2c) {
      std::lock_guard<std::mutex> lock(planner_mutex());
      allocate(real_in, n);
      allocate(half_out, n / 2 + 1);
      probe_planning_memory();
      r2c = fftw_plan_dft_r2c_1d(static_cast<int>(n), real_in, half_out, FFTW_ESTIMATE);
    }
    return r2c;
  }
  fftw_plan complex_plan() {
    if (!c2c_backward) {
      std::lock_guard<std::mutex> lock(planner_mutex());
      allocate(full_in, n);
      allocate(full_out, n);
      probe_planning_memory();
      c2c_backward =
          fftw_plan_dft_1d(static_cast<int>(n), full_in, full_out, FFTW_BACKWARD, FFTW_ESTIMATE);
    }
    return c2c_backward;
  }
  // c2r overwrites its input: it reads full_in (n/2 + 1 values) and writes real_in.
  fftw_plan real_plan() {
    if (!c2r) {
      std::lock_guard<std::mutex> lock(planner_mutex());
      allocate(full_in, n);
      allocate(real_in, n);
      probe_planning_memory();
      c2r = fftw_plan_dft_c2r_1d(static_cast<int>(n), full_in, real_in, FFTW_ESTIMATE);
    }
    return c2r;
  }
  bool halfcomplex() const;
  // The plan from a real input aligned as `r` into half_out (FFTW_ESTIMATE: `r` not touched).
  fftw_plan buffered_plan(double* r) {
    const int wanted = fftw_alignment_of(r);
    for (const auto& [alignment, plan] : r2c_buffered)
      if (alignment == wanted) return plan;
    std::lock_guard<std::mutex> lock(planner_mutex());
    allocate(half_out, n / 2 + 1);
    probe_planning_memory();
    const fftw_plan plan = fftw_plan_dft_r2c_1d(static_cast<int>(n), r, half_out, FFTW_ESTIMATE);
    if (!plan) throw std::bad_alloc();
    r2c_buffered.emplace_back(wanted, plan);
    return plan;
  }
  // The halfcomplex plan of `kind` (FFTW_R2HC or FFTW_HC2R) in place on r, kept in the
  // forward or inverse in-place slot.
  fftw_plan halfcomplex_plan(fftw_r2r_kind kind, double* r) {
    fftw_plan& plan = kind == FFTW_R2HC ? r2c_in_place : c2r_in_place;
    std::lock_guard<std::mutex> lock(planner_mutex());
    if (plan) fftw_destroy_plan(plan);
    plan = nullptr;
    probe_planning_memory(3);  // its tables take 1.8 bytes a point
    plan = fftw_plan_r2r_1d(static_cast<int>(n), r, r, kind, FFTW_ESTIMATE);
    if (!plan) throw std::bad_alloc();
    return plan;
  }
  void drop_in_place_plans() {
    std::lock_guard<std::mutex> lock(planner_mutex());
    for (fftw_plan* p : {&r2c_in_place, &c2r_in_place}) {
      if (*p) fftw_destroy_plan(*p);
      *p = nullptr;
    }
  }
  // In-place plans on `data` (FFTW_ESTIMATE plans without touching it), made again for an
  // array aligned otherwise.
  fftw_plan in_place_plan(bool forward, std::complex<double>* data) {
    auto* c = reinterpret_cast<fftw_complex*>(data);
    auto* r = reinterpret_cast<double*>(data);
    fftw_plan& plan = forward ? r2c_in_place : c2r_in_place;
    int& alignment = forward ? r2c_alignment : c2r_alignment;
    const int wanted = fftw_alignment_of(r);
    if (!plan || wanted != alignment) {
      std::lock_guard<std::mutex> lock(planner_mutex());
      // The plan for this alignment if one was made (a long record's are never kept).
      auto& other = forward ? r2c_other : c2r_other;
      if (plan && n <= kLargestKeptPlan) {
        other.emplace_back(alignment, plan);
        plan = nullptr;
      }
      for (auto it = other.begin(); it != other.end(); ++it) {
        if (it->first == wanted) {
          plan = it->second;
          alignment = wanted;
          other.erase(it);
          return plan;
        }
      }
      if (plan) fftw_destroy_plan(plan);
      plan = nullptr;
      probe_planning_memory();
      plan = forward ? fftw_plan_dft_r2c_1d(static_cast<int>(n), r, c, FFTW_ESTIMATE)
                     : fftw_plan_dft_c2r_1d(static_cast<int>(n), c, r, FFTW_ESTIMATE);
      if (!plan) throw std::bad_alloc();
      alignment = wanted;
    }
    return plan;
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
  const fftw_plan plan = impl_->forward_plan();  // allocates the buffers
  std::memset(impl_->real_in, 0, sizeof(double) * n);
  for (Eigen::Index j = 0; j < x.size(); ++j) impl_->real_in[j] = x(j);
  fftw_execute(plan);
  Eigen::VectorXcd out(n / 2 + 1);
  for (Eigen::Index k = 0; k <= n / 2; ++k) {
    out(k) = {impl_->half_out[k][0], impl_->half_out[k][1]};
  }
  return out;
}

Eigen::VectorXcd Fft::inverse_complex(const Eigen::Ref<const Eigen::VectorXcd>& spectrum) {
  const Eigen::Index n = impl_->n;
  assert(spectrum.size() == n);
  const fftw_plan plan = impl_->complex_plan();
  for (Eigen::Index k = 0; k < n; ++k) {
    impl_->full_in[k][0] = spectrum(k).real();
    impl_->full_in[k][1] = spectrum(k).imag();
  }
  fftw_execute(plan);
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
  const fftw_plan plan = impl_->real_plan();
  for (Eigen::Index k = 0; k <= n / 2; ++k) {
    impl_->full_in[k][0] = half_spectrum(k).real();
    impl_->full_in[k][1] = half_spectrum(k).imag();
  }
  fftw_execute(plan);
  Eigen::VectorXd out(n);
  const double scale = 1.0 / static_cast<double>(n);
  for (Eigen::Index j = 0; j < n; ++j) out(j) = impl_->real_in[j] * scale;
  return out;
}

namespace {

// Moves a[i] to a[to(i)] for every i in [0, size), `to` a permutation: each cycle once, a bit
// a value marking what has moved.
template <typename To>
void permute(double* a, Eigen::Index size, To to) {
  std::vector<bool> moved(static_cast<size_t>(size), false);
  for (Eigen::Index start = 0; start < size; ++start) {
    if (moved[static_cast<size_t>(start)]) continue;
    double carried = a[start];
    Eigen::Index at = start;
    do {
      at = to(at);
      std::swap(carried, a[at]);
      moved[static_cast<size_t>(at)] = true;
    } while (at != start);
  }
}

// Where the value at i of FFTW's halfcomplex order for even n (Re X_0 .. Re X_{n/2}, then
// Im X_{n/2-1} .. Im X_1; n and n + 1 hold the zero imaginary parts of X_0 and X_{n/2})
// goes in the interleaved one-sided spectrum.
Eigen::Index interleaved_place(Eigen::Index i, Eigen::Index n) {
  if (i <= n / 2) return 2 * i;
  if (i < n) return 2 * (n - i) + 1;
  return i == n ? 1 : n + 1;
}

// Its inverse: where the interleaved value at d goes in halfcomplex order.
Eigen::Index halfcomplex_place(Eigen::Index d, Eigen::Index n) {
  if (d % 2 == 0) return d / 2;
  if (d == 1) return n;
  if (d == n + 1) return n + 1;
  return n - (d - 1) / 2;
}

}  // namespace

// Above kLargestKeptPlan an even size is transformed by FFTW's halfcomplex (r2r) plan, whose
// tables take 1.8 bytes a point where the r2c plan's take 8.6 (measured at 2e7 points), and
// the halfcomplex order is permuted in place into the interleaved one: a long record's
// spectrum then costs little beyond its own buffer.
bool Fft::Impl::halfcomplex() const { return n > kLargestKeptPlan && n % 2 == 0; }

void Fft::forward_in_place(std::complex<double>* data) {
  auto* r = reinterpret_cast<double*>(data);
  if (impl_->halfcomplex()) {
    const Eigen::Index n = impl_->n;
    fftw_execute_r2r(impl_->halfcomplex_plan(FFTW_R2HC, r), r, r);
    impl_->drop_in_place_plans();
    r[n] = r[n + 1] = 0.0;
    permute(r, n + 2, [n](Eigen::Index i) { return interleaved_place(i, n); });
    return;
  }
  fftw_plan p = impl_->in_place_plan(true, data);
  fftw_execute_dft_r2c(p, r, reinterpret_cast<fftw_complex*>(data));
  if (impl_->n > kLargestKeptPlan) impl_->drop_in_place_plans();
}

void Fft::forward_through_buffer(std::complex<double>* data) {
  if (impl_->n > kLargestBufferedForward) {
    forward_in_place(data);
    return;
  }
  auto* r = reinterpret_cast<double*>(data);
  const fftw_plan plan = impl_->buffered_plan(r);  // allocates half_out on the first call
  fftw_execute_dft_r2c(plan, r, impl_->half_out);
  std::memcpy(static_cast<void*>(data), impl_->half_out,
              sizeof(fftw_complex) * static_cast<size_t>(impl_->n / 2 + 1));
}

void Fft::inverse_real_in_place(std::complex<double>* data) {
  auto* r = reinterpret_cast<double*>(data);
  const Eigen::Index n = impl_->n;
  if (impl_->halfcomplex()) {
    permute(r, n + 2, [n](Eigen::Index d) { return halfcomplex_place(d, n); });
    fftw_execute_r2r(impl_->halfcomplex_plan(FFTW_HC2R, r), r, r);
    impl_->drop_in_place_plans();
  } else {
    fftw_plan p = impl_->in_place_plan(false, data);
    fftw_execute_dft_c2r(p, reinterpret_cast<fftw_complex*>(data), r);
    if (n > kLargestKeptPlan) impl_->drop_in_place_plans();
  }
  const double scale = 1.0 / static_cast<double>(n);
  for (Eigen::Index j = 0; j < n; ++j) r[j] *= scale;
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
