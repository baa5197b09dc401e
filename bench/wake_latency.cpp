// peelcd_wake_latency: how long a WorkerPool's second lane takes to start a job, against how much
// memory the process holds and how long the lane slept while the calling thread worked.
// peelcd's threads (WorkerPool: the World's lanes, the host resolve) sleep between jobs; on bare
// metal a wake costs microseconds, but on some virtual machines the first wake of a thread that
// slept while its process changed or held gigabytes stalls for milliseconds per GB, a cost of the
// platform that falls on any threaded method timed after seconds of single-threaded work
// (docs/performance.md, "Threads"). Prints one line per (resident MB, busy gap) with the mean and
// largest delay from run() to the lane's start over the repeats. Not installed.
//   peelcd_wake_latency [--mb 250,1000,3500] [--gaps 5,50,500,2000] [--repeats 4]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "peelcd/core/worker_pool.h"

namespace {

using Clock = std::chrono::steady_clock;

std::vector<int> list_of(const char* text, const char* option) {
  std::vector<int> v;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const long x = std::strtol(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0' || x < 0 || x > 1000000) {
      std::fprintf(stderr, "peelcd_wake_latency: %s '%s': expected non-negative integers separated by commas\n", option, text);
      std::exit(2);
    }
    v.push_back(int(x));
  }
  if (v.empty()) {
    std::fprintf(stderr, "peelcd_wake_latency: %s is empty\n", option);
    std::exit(2);
  }
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> mbs{250, 1000, 3500}, gaps{5, 50, 500, 2000};
  int repeats = 4;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (i + 1 < argc && a == "--mb") {
      mbs = list_of(argv[++i], "--mb");
    } else if (i + 1 < argc && a == "--gaps") {
      gaps = list_of(argv[++i], "--gaps");
    } else if (i + 1 < argc && a == "--repeats") {
      repeats = list_of(argv[++i], "--repeats").front();
      if (repeats < 1) repeats = 1;
    } else {
      std::fprintf(stderr, "usage: peelcd_wake_latency [--mb 250,1000,3500] [--gaps 5,50,500,2000] [--repeats 4]\n");
      return 2;
    }
  }
  std::sort(mbs.begin(), mbs.end());
  peelcd::WorkerPool pool(2);
  Clock::time_point sent;
  double delay = 0.0;
  auto job = [&](unsigned lane) {
    if (lane == 1) delay = std::chrono::duration<double, std::milli>(Clock::now() - sent).count();
  };
  std::vector<std::unique_ptr<char[]>> held;  // 1 MB blocks, every page written once
  std::printf("%12s %12s %14s %14s\n", "resident MB", "busy gap ms", "mean delay ms", "max delay ms");
  for (int mb : mbs) {
    while (held.size() < std::size_t(mb)) {
      held.emplace_back(new char[1 << 20]);
      std::memset(held.back().get(), 1, 1 << 20);
    }
    pool.run(job);  // the lane wakes once after the allocation, untimed
    for (int gap : gaps) {
      double sum = 0.0, most = 0.0;
      for (int r = 0; r < repeats; ++r) {
        const auto t0 = Clock::now();
        volatile double spin = 0.0;  // the calling thread busy, the lane asleep
        while (Clock::now() - t0 < std::chrono::milliseconds(gap)) spin = spin + 1.0;
        sent = Clock::now();
        pool.run(job);
        sum += delay;
        most = std::max(most, delay);
      }
      std::printf("%12d %12d %14.3f %14.3f\n", mb, gap, sum / repeats, most);
      std::fflush(stdout);
    }
  }
  return 0;
}
