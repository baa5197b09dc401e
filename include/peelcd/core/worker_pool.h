#pragma once
// A fixed set of threads that run one job at a time, split into lanes: the host resolve of the
// k-buffer (core/image/kbuffer.h) runs on one per gl::Pipeline, the World's and the frame API's
// loops over pairs and tasks on one each. Threads live as long as the pool; running a job
// allocates nothing. A lane done with a job spins up to 50 microseconds for the next before it
// sleeps (core/worker_pool.cpp), as the calling thread does for the lanes' ends.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace peelcd {

class WorkerPool {
 public:
  explicit WorkerPool(unsigned lanes = 0);  // 0: the hardware's threads, at most 8
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  unsigned lanes() const { return unsigned(workers_.size() + 1); }
  // Calls fn(lane) once for every lane in [0, lanes()), lane 0 on the calling thread, and
  // returns when all have returned; the first exception thrown by a lane is rethrown here.
  template <class F>
  void run(F& fn) {
    run_erased([](void* f, unsigned lane) { (*static_cast<F*>(f))(lane); }, &fn);
  }
  // Calls fn(i, lane) for every i in [0, n) over the lanes. Lane l starts on the l-th of
  // lanes() contiguous ranges of [0, n), front to back; a lane done with its range takes the
  // others' last items, back to front. So the same n gives item i the same lane from call to
  // call, stolen items aside: what an item's work wrote in one loop (a task's candidates, a
  // body's world copy) is read in the next from the cache of the core that wrote it. Taking
  // items from one shared counter instead puts each on either lane at random: the World's
  // 1,000-ball pile at 2 threads took 0.62-0.73x its one-thread frame that way against
  // 0.50-0.61x (docs/performance.md, "Threads").
  template <class F>
  void for_each(std::size_t n, F&& fn) {
    const unsigned lanes = this->lanes();
    if (lanes == 1 || n <= 1) {
      for (std::size_t i = 0; i < n; ++i) fn(i, 0u);
      return;
    }
    if (n > kMaxItems) {  // (past 32 bits: one shared counter)
      std::atomic<std::size_t> next{0};
      auto job = [&](unsigned lane) {
        for (std::size_t i = next.fetch_add(1); i < n; i = next.fetch_add(1)) fn(i, lane);
      };
      run(job);
      return;
    }
    for (unsigned l = 0; l < lanes; ++l)
      ranges_[l].items.store(pack(n * l / lanes, n * (l + 1) / lanes), std::memory_order_relaxed);
    auto job = [&](unsigned lane) {
      std::size_t i;
      while (take_front(ranges_[lane].items, i)) fn(i, lane);
      for (unsigned k = 1; k < lanes; ++k) {
        std::atomic<std::uint64_t>& victim = ranges_[(lane + k) % lanes].items;
        while (take_back(victim, i)) fn(i, lane);
      }
    };
    run(job);
  }

 private:
  using Erased = void (*)(void*, unsigned);
  void run_erased(Erased fn, void* context);
  void work(unsigned lane);
  void call(unsigned lane);

  // for_each(): a lane's items left, [begin, end) packed in one word (begin high).
  static constexpr std::size_t kMaxItems = 0xffffffffu;
  struct alignas(64) Range {
    std::atomic<std::uint64_t> items{0};
  };
  static std::uint64_t pack(std::size_t begin, std::size_t end) { return std::uint64_t(begin) << 32 | end; }
  static bool take_front(std::atomic<std::uint64_t>& r, std::size_t& i) {
    std::uint64_t v = r.load(std::memory_order_relaxed);
    for (;;) {
      const std::size_t begin = std::size_t(v >> 32), end = std::size_t(v & kMaxItems);
      if (begin >= end) return false;
      if (r.compare_exchange_weak(v, pack(begin + 1, end), std::memory_order_relaxed)) {
        i = begin;
        return true;
      }
    }
  }
  static bool take_back(std::atomic<std::uint64_t>& r, std::size_t& i) {
    std::uint64_t v = r.load(std::memory_order_relaxed);
    for (;;) {
      const std::size_t begin = std::size_t(v >> 32), end = std::size_t(v & kMaxItems);
      if (begin >= end) return false;
      if (r.compare_exchange_weak(v, pack(begin, end - 1), std::memory_order_relaxed)) {
        i = end - 1;
        return true;
      }
    }
  }
  std::vector<Range> ranges_;  // one per lane
  std::vector<std::thread> workers_;  // lanes 1 .. lanes() - 1
  std::mutex mutex_;
  std::condition_variable start_, done_;
  std::atomic<std::uint64_t> generation_{0};
  std::atomic<std::size_t> finished_{0};
  std::atomic<bool> stop_{false};
  Erased job_ = nullptr;
  void* context_ = nullptr;
  std::exception_ptr error_;
};

}  // namespace peelcd
