#pragma once
// What the commands of the peelcd executable share: one small header. Each command (or family)
// lives in its own file (apps/cmd_*.cpp) and registers itself with add_*_commands(); apps/main.cpp
// parses the command line and runs the one chosen.
#include "data.h"
#include "peelcd/backends.h"
#include "peelcd/bench/peers.h"
#include "peelcd/bench/suite.h"
#include "peelcd/core/image/detector.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/io/costs.h"
#include "peelcd/io/mesh_io.h"
#include "peelcd/core/options.h"
#include "peelcd/eval/scenes.h"
#include "peelcd/gl/gl_stage.h"
#include "peelcd/io/error.h"
#include "peelcd/io/output.h"
#include "peelcd/io/scene.h"
#include "peelcd/oracle/dump.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <unistd.h>
#include <vector>

namespace peelcd::cli {

// A registered command: its CLI11 subcommand and what runs it (returns the exit status).
struct Command {
  CLI::App* app;
  std::function<int()> run;
};
std::vector<Command> add_detect_commands(CLI::App& app);    // detect, explain (cmd_detect.cpp)
std::vector<Command> add_dump_commands(CLI::App& app);      // dump (cmd_dump.cpp)
std::vector<Command> add_golden_commands(CLI::App& app);    // golden record|compare|compare-dumps (cmd_dump.cpp)
std::vector<Command> add_simulate_commands(CLI::App& app);  // simulate (cmd_simulate.cpp)
std::vector<Command> add_bench_commands(CLI::App& app);     // bench (cmd_bench.cpp)
std::vector<Command> add_sweep_commands(CLI::App& app);     // sweep, sweep merge (cmd_sweep.cpp)
std::vector<Command> add_eval_commands(CLI::App& app);      // classes, calibrate (cmd_eval.cpp)

constexpr int kExitBadInput = 2;

// kDefaultBackend: peelcd/backends.h's (the software reference where it was built, else EGL).

// Output options (--json, --csv, --plot, --out, --report): an empty value is a mistake, refused
// at parse time (exit 2), not read as "no output".
extern const CLI::Validator kOutputPath;

// Numbers with messages a person can read (CLI11's own let "nan" through).
extern const CLI::Validator kFinite, kPositive, kNonNegative;

// The image stage of a run (make_image_stage(), peelcd/backends.h) and the detector over it.
struct Runner {
  std::shared_ptr<ImageStage> stage;
  gl::GlImageStage* gl = nullptr;  // the GL stage, or null for the CPU stage
  std::unique_ptr<Detector> detector;

  const std::string& backend() const { return stage->backend(); }
  const std::string& renderer() const { return stage->renderer(); }
  // GL stage options of one configuration (ignored by the CPU stage).
  gl::GlOptions gl_options;  // the GL stage's settings in use
  void use(const gl::GlOptions& options) {
    gl_options = options;
    if (gl) gl->set_options(options);
  }
  const gl::GlOptions* gl_settings() const { return gl ? &gl_options : nullptr; }
};

// `costs`: the router's cost models from that file; empty: $PEELCD_COSTS's, else the built-in.
Runner make_runner(const std::string& backend, const gl::GlOptions& options = {}, const std::string& costs = {});

struct DetectArgs {
  std::string scene;
  std::vector<std::string> inputs;  // detect: one scene file, or mesh files
  // The frame's options as given on the command line: each row of the option table
  // (peelcd/core/options.h) with a flag, by key; a boolean's "--no-" form as "false".
  std::map<std::string, std::string> options;
  std::map<std::string, bool> flags_on, flags_off;  // boolean rows: --KEY, --no-KEY
  std::map<std::string, std::string> gl;  // GL stage options by gl_option_table() key
  bool paper = false;
  double max_miss = NAN;  // percent; NaN = report only
  std::string json_out;
  int repeat = 1;
  bool gpu_timers = false;  // time the image stage's GPU passes (timer queries)
  int views = 0;  // 0 = not given
  bool check = false;
  bool quiet = false;
  bool list = false;    // print every colliding triangle pair (default: the summary only)
  bool pcs = false;     // print every pair's PCS
  std::string costs;    // --costs: the router's cost models
  bool status = false;  // exit 1 when nothing collides
  int explain_misses = 0;  // detect --check: explain the first N missed pairs
  std::string backend = kDefaultBackend;
};

// Progress on long work, in one place: a bar redrawn in place on stderr, and one-line phases
// ("loading meshes", "running the frame") cleared when done, only when stderr is a terminal, so
// logs and pipes stay clean. A command that prints a line per step on a terminal stdout (simulate,
// golden compare) asks for the bar only when stdout is redirected (`unless_stdout_tty`).
struct Progress {
  std::string unit;
  bool tty;  // draw at all
  explicit Progress(std::string u = "frames", bool unless_stdout_tty = false)
      : unit(std::move(u)), tty(isatty(STDERR_FILENO) && !(unless_stdout_tty && isatty(STDOUT_FILENO))) {}
  void operator()(std::size_t done, std::size_t total) const {
    if (!tty) return;
    const int width = 40, filled = int(width * done / std::max<std::size_t>(total, 1));
    std::fprintf(stderr, "\r[%s%s] %zu/%zu %s", std::string(filled, '#').c_str(),
                 std::string(width - filled, ' ').c_str(), done, total, unit.c_str());
    if (done == total) std::fprintf(stderr, "\n");
  }
  void phase(const std::string& what) const {
    if (tty) std::fprintf(stderr, "\r\033[K%s", what.c_str());
  }
  void clear() const {
    if (tty) std::fprintf(stderr, "\r\033[K");
  }
};

// `text` parsed by `parse` (returning std::optional), or an InputError: `unknown` "text"
// (expected `expected`).
template <class Parse>
auto parsed(const std::string& text, Parse parse, const std::string& unknown, const char* expected) {
  const auto m = parse(text);
  if (!m) throw InputError(unknown + " \"" + text + "\" (expected " + expected + ")");
  return *m;
}

// A scene's input files: the scene file itself (when there is one) and every mesh it names.
std::vector<std::string> scene_inputs(const Scene& scene);
// GL stage options: the scene file's, overridden by the command line's.
gl::GlOptions merged_gl_options(const Scene& scene, const std::map<std::string, std::string>& given = {});
// The GL stage's flags, generated from gl_option_table() (every row, or those in `keys`).
void add_gl_options(CLI::App* c, std::map<std::string, std::string>& values, const std::set<std::string>& keys = {});
// Command-line values override the scene file's (each checked by the option table's rules).
DetectOptions merged_options(const Scene& scene, const DetectArgs& a);
// --backend, one help text: every image stage, or (`gl_only`) the GL ones.
CLI::Option* add_backend_option(CLI::App* c, std::string& backend, bool gl_only = false);
// The frame's options, one flag per row of the option table, and the GL stage's.
void add_frame_options(CLI::App* c, DetectArgs& d);
// --json / --csv outputs: atomic, never destroying (peelcd/io/output.h). "-" is stdout.
void write_output(const std::string& path, const std::string& text);
using bench::median;
// detect's input (and dump's, explain's): one scene file, a glTF scene, or two or more meshes.
Scene detect_input(const std::vector<std::string>& inputs, const std::string& command = "peelcd detect", bool self = false);
// One frame with every layer captured (every ROI peeled, Stage::image).
oracle::Dump capture_frame(const std::vector<Object>& objects, const DetectOptions& options, Runner& runner);
// The broad phase's overlapping object pairs: the ROIs of a frame (before culling).
std::size_t count_overlapping_pairs(const std::vector<Object>& objects);
// test1, test2 or crowd.
std::unique_ptr<Sequence> make_sequence(const std::string& name, std::size_t frames, bool rigid = true,
                                        std::size_t objects = 200);
using bench::score_frame;
// "K/N" (1 <= K <= N): which slice of a sharded run this is, as {K - 1, N}; {0, 1} when empty.
std::pair<std::size_t, std::size_t> parse_shard(const std::string& text, const std::string& what);

}  // namespace peelcd::cli
