#pragma once
// A CPU image stage whose first frame waits in begin_frame() until released: holds a frame open
// on one thread while the test calls the same Detector, World or CollisionWorld from another
// (the one-thread-at-a-time guard's tests).
#include "peelcd/core/image/cpu_stage.h"

#include <condition_variable>
#include <mutex>

namespace peelcd::test {

class GatedStage final : public ImageStage {
 public:
  const std::string& backend() const override { return inner_.backend(); }
  const std::string& renderer() const override { return inner_.renderer(); }
  const std::string& version() const override { return inner_.version(); }
  int max_resolution() const override { return inner_.max_resolution(); }
  void begin_frame() override {  // only the first frame waits
    std::unique_lock<std::mutex> lock(m_);
    if (entered_) return;
    entered_ = true;
    cv_.notify_all();
    cv_.wait(lock, [&] { return released_; });
  }
  void peel(const PeelJob& job, PeelResult& out, Timings& timings) override { inner_.peel(job, out, timings); }
  // Returns once a frame is inside begin_frame().
  void wait_entered() {
    std::unique_lock<std::mutex> lock(m_);
    cv_.wait(lock, [&] { return entered_; });
  }
  void release() {
    std::lock_guard<std::mutex> lock(m_);
    released_ = true;
    cv_.notify_all();
  }

 private:
  CpuImageStage inner_;
  std::mutex m_;
  std::condition_variable cv_;
  bool entered_ = false, released_ = false;
};

}  // namespace peelcd::test
