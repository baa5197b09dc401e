#pragma once
// A fixed set of threads that run one job at a time, split into lanes: the host resolve of the
// k-buffer (core/image/kbuffer.h) runs on one per gl::Pipeline. Threads live as long as the pool;
// running a job allocates nothing.
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

 private:
  using Erased = void (*)(void*, unsigned);
  void run_erased(Erased fn, void* context);
  void work(unsigned lane);
  void call(unsigned lane);

  std::vector<std::thread> workers_;  // lanes 1 .. lanes() - 1
  std::mutex mutex_;
  std::condition_variable start_, done_;
  std::uint64_t generation_ = 0;
  std::size_t finished_ = 0;
  bool stop_ = false;
  Erased job_ = nullptr;
  void* context_ = nullptr;
  std::exception_ptr error_;
};

}  // namespace peelcd
