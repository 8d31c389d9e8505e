// Independent jobs on every core.
//
// parallel_for(n, threads, make_state, body) runs body(i, state) for every i in
// [0, n) on min(threads, n) workers (threads = 0: one per core). Each worker
// makes its own state once (FFT plans, say: they are not shared between
// threads). Every job runs even when another throws; afterwards the exception
// of the lowest-numbered failed job is rethrown, so errors are reported in a
// stable order.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <thread>
#include <vector>

namespace jointlab {

/// The worker count a `--threads` value asks for: itself, or every core (at least 1) for 0.
inline unsigned threads_or_cores(unsigned threads) {
  return threads ? threads : std::max(1u, std::thread::hardware_concurrency());
}

/// Runs body(i, state) for i in [0, n) on worker threads, each with its own make_state().
template <typename MakeState, typename Body>
void parallel_for(std::size_t n, unsigned threads, MakeState make_state, Body body) {
  const unsigned workers = static_cast<unsigned>(
      std::min<std::size_t>(threads_or_cores(threads), std::max<std::size_t>(n, 1)));
  std::vector<std::exception_ptr> errors(n);
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    auto state = make_state();
    for (std::size_t i = next++; i < n; i = next++) {
      try {
        body(i, state);
      } catch (...) {
        errors[i] = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned w = 1; w < workers; ++w) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

}  // namespace jointlab
