#include "peelcd/core/worker_pool.h"

#include <algorithm>
#include <chrono>
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace peelcd {

WorkerPool::WorkerPool(unsigned lanes) {
  if (lanes == 0) lanes = std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
  ranges_ = std::vector<Range>(lanes);
  for (unsigned i = 1; i < lanes; ++i) workers_.emplace_back([this, i] { work(i); });
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  start_.notify_all();
  for (std::thread& w : workers_) w.join();
}

void WorkerPool::call(unsigned lane) {
  try {
    job_(context_, lane);
  } catch (...) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!error_) error_ = std::current_exception();
  }
}

namespace {
// Waits up to kSpinFor for ready() before the caller sleeps on the pool's condition: a frame's
// loops follow one another within microseconds, and a lane asleep needs the scheduler to wake it
// for the next (and the calling thread, for the last lane's end). Bounded, so a pool idle
// between frames or sharing its cores with other work sleeps soon.
template <class Ready>
bool spin_until(Ready ready) {
  constexpr auto kSpinFor = std::chrono::microseconds(50);
  const auto until = std::chrono::steady_clock::now() + kSpinFor;
  for (unsigned i = 0;; ++i) {
    if (ready()) return true;
#if defined(__x86_64__) || defined(__i386__)
    _mm_pause();
#endif
    if ((i & 63) == 63 && std::chrono::steady_clock::now() > until) return ready();
  }
}
}  // namespace

void WorkerPool::work(unsigned lane) {
  std::uint64_t seen = 0;
  for (;;) {
    spin_until([&] { return stop_.load(std::memory_order_acquire) || generation_.load(std::memory_order_acquire) != seen; });
    {
      std::unique_lock<std::mutex> lock(mutex_);
      start_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
    }
    call(lane);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++finished_;
    }
    done_.notify_one();
  }
}

void WorkerPool::run_erased(Erased fn, void* context) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    job_ = fn;
    context_ = context;
    finished_ = 0;
    error_ = nullptr;
    ++generation_;
  }
  start_.notify_all();
  call(0);
  spin_until([&] { return finished_.load(std::memory_order_acquire) == workers_.size(); });
  std::exception_ptr error;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return finished_ == workers_.size(); });
    error = error_;
  }
  if (error) std::rethrow_exception(error);
}

}  // namespace peelcd
