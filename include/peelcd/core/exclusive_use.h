#pragma once
// One thread at a time per Detector or World: a second thread entering while the first is inside
// (a frame, or a change of bodies) gets a clear error instead of racing on the object's state.
// Re-entry from the owning thread (public functions that call one another) passes.
#include <atomic>
#include <stdexcept>
#include <string>
#include <thread>

namespace peelcd {

class ExclusiveUse {
 public:
  // `what`: the object, for the message ("peelcd::World").
  ExclusiveUse(std::atomic<std::thread::id>& owner, const char* what) : owner_(owner) {
    const std::thread::id me = std::this_thread::get_id();
    std::thread::id none{};
    if (owner_.compare_exchange_strong(none, me)) {
      held_ = true;
    } else if (none != me) {
      throw std::logic_error(std::string(what) + ": called from a second thread while another uses it; one serves one "
                             "thread at a time (make one per thread, or hold a lock around it)");
    }
  }
  ~ExclusiveUse() {
    if (held_) owner_.store(std::thread::id{});
  }
  ExclusiveUse(const ExclusiveUse&) = delete;
  ExclusiveUse& operator=(const ExclusiveUse&) = delete;

 private:
  std::atomic<std::thread::id>& owner_;
  bool held_ = false;
};

}  // namespace peelcd
