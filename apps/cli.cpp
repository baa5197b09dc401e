#include "cli.h"

#include "peelcd/core/broad_phase.h"
#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/exact/reference.h"

namespace peelcd::cli {

// Output options (--json, --csv, --plot, --out, --report): an empty value is a mistake, refused
// at parse time (exit 2), not read as "no output".
const CLI::Validator kOutputPath(
    [](std::string& value) { return value.empty() ? std::string("an empty path (give a file name, or - for stdout)") : std::string(); },
    "");


// Number checks with messages a person can read. CLI11's own let "nan" through (every
// comparison with NaN is false; a NaN here would read as "not given") and print the range up
// to DBL_MAX in full.
CLI::Validator finite_number(bool (*ok)(double), const char* need, const char* name) {
  return CLI::Validator(
      [ok, need](std::string& text) -> std::string {
        double v = 0.0;
        std::size_t used = 0;
        try {
          v = std::stod(text, &used);
        } catch (const std::out_of_range&) {
          return "Value " + text + " is not a finite number";
        } catch (const std::exception&) {
          return "Value " + text + " is not a number";
        }
        if (used != text.size()) return "Value " + text + " is not a number";
        if (!std::isfinite(v)) return "Value " + text + " is not a finite number";
        return ok(v) ? std::string() : "Value " + text + " " + need;
      },
      name);
}
const CLI::Validator kFinite = finite_number([](double) { return true; }, "", "FINITE");
const CLI::Validator kPositive = finite_number([](double v) { return v > 0.0; }, "is not positive", "POSITIVE");
const CLI::Validator kNonNegative = finite_number([](double v) { return v >= 0.0; }, "is negative", "NONNEGATIVE");


Runner make_runner(const std::string& backend, const gl::GlOptions& options, const std::string& costs) {
  Runner r;
  r.stage = make_image_stage(backend, options);  // peelcd/backends.h
  if (!costs.empty()) apply_cost_models(*r.stage, costs);  // peelcd/io/costs.h
  else apply_cost_models_from_env(*r.stage);
  r.gl = dynamic_cast<gl::GlImageStage*>(r.stage.get());
  r.gl_options = options;
  r.detector = std::make_unique<Detector>(r.stage);
  return r;
}

// A scene's input files: the scene file itself (when there is one) and every mesh it names.
std::vector<std::string> scene_inputs(const Scene& scene) {
  std::vector<std::string> inputs;
  if (std::filesystem::is_regular_file(scene.path)) inputs.push_back(scene.path);
  for (const SceneObject& o : scene.objects) inputs.push_back(o.mesh_path);
  return inputs;
}

// GL stage options: the scene file's, overridden by the command line's (gl_option_table()'s rows
// by key, as add_gl_options() stored them); a bad value is an InputError naming the flag.
gl::GlOptions merged_gl_options(const Scene& scene, const std::map<std::string, std::string>& given) {
  gl::GlOptions o = scene.gl;
  for (const gl::GlOptionSpec& spec : gl::gl_option_table()) {
    const auto it = given.find(spec.key);
    if (it == given.end()) continue;
    const std::string problem = gl::set_gl_option(o, spec.key, it->second);
    if (!problem.empty()) {
      const std::size_t colon = problem.find(':');  // "KEY: unknown value ..." -> "--flag: unknown value ..."
      throw InputError(std::string("peelcd: ") + spec.flag + problem.substr(colon == std::string::npos ? 0 : colon));
    }
  }
  return o;
}

// One flag per row of gl_option_table() (all rows, or those in `keys`), its help the table's: a
// choice's value stored by key in `values`; a boolean's flag turns the setting off ("false").
void add_gl_options(CLI::App* c, std::map<std::string, std::string>& values, const std::set<std::string>& keys) {
  const gl::GlOptions defaults;
  for (const gl::GlOptionSpec& spec : gl::gl_option_table()) {
    if (!keys.empty() && !keys.count(spec.key)) continue;
    const std::string key = spec.key;
    if (!*spec.choices) {
      c->add_flag_callback(
          spec.flag, [&values, key] { values[key] = "false"; },
          "GL stage, sets " + key + " false (default " + spec.get(defaults) + "): " + spec.help);
      continue;
    }
    std::string choices = spec.choices;
    c->add_option_function<std::string>(
         spec.flag, [&values, key](const std::string& v) { values[key] = v; },
         "GL stage, " + key + " (default " + spec.get(defaults) + "): " + spec.help)
        ->type_name("{" + choices + "}");
  }
}

// Command-line values override the scene file's (each checked by the option table's rules, the
// message naming the flag).
DetectOptions merged_options(const Scene& scene, const DetectArgs& a) {
  DetectOptions o = scene.options;
  if (a.paper) {  // the paper's configuration, at the scene's resolution and budget
    const DetectOptions p = paper_options();
    const int res = o.resolution, budget = o.budget;
    o = p;
    o.resolution = res;
    o.budget = budget;
  }
  // --theta/--phi alone turn the paper's frame (roll 0) there, as a scene's "view" does.
  bool direction = false;
  for (const OptionSpec& spec : option_table())
    direction = direction || (sets_view_direction(spec) && a.options.count(spec.key));
  if (direction && !a.options.count("roll")) o.roll = 0.0;
  for (const OptionSpec& spec : option_table()) {
    if (!spec.flag) continue;
    if (spec.kind == OptionSpec::Kind::boolean) {
      const bool on = a.flags_on.count(spec.key) && a.flags_on.at(spec.key);
      const bool off = a.flags_off.count(spec.key) && a.flags_off.at(spec.key);
      if (on && off)
        throw InputError(std::string("peelcd: ") + spec.flag + " and --no-" + (spec.flag + 2) + " contradict each other");
      if (on || off) spec.set(o, OptionValue(on));
      continue;
    }
    const auto given = a.options.find(spec.key);
    if (given == a.options.end()) continue;
    std::string problem;
    const OptionValue value = parse_option(spec, given->second, problem);
    if (!problem.empty()) throw InputError(std::string("peelcd: ") + spec.flag + ": " + problem);
    spec.set(o, value);
  }
  return o;
}

// Writes `text` to `path` through a temporary file and a rename, so a failure never leaves a
// half-written file behind. "-" is stdout.
// --json / --csv outputs: atomic, never destroying (include/peelcd/io/output.h).
void write_output(const std::string& path, const std::string& text) { write_output_file(path, text + "\n", "peelcd: output"); }


// detect's input: one scene file, or mesh files (identity transforms, default options): two or
// more, or one with `self` (its self-collision).
Scene detect_input(const std::vector<std::string>& inputs, const std::string& command, bool self) {
  const auto is_scene = [](const std::string& p) { return std::filesystem::path(p).extension() == ".json"; };
  if (inputs.size() == 1) {
    if (is_node_scene(inputs[0])) return scene_from_meshes(inputs);  // a glTF scene: one object per node
    if (!is_scene(inputs[0]) && self) return scene_from_meshes(inputs);  // one mesh against itself
    if (!is_scene(inputs[0]))
      throw InputError(command + ": '" + inputs[0] + "' is one mesh: give a scene file (.json), a glTF scene (.gltf, .glb), two or more meshes, or --self for its self-collision");
    return load_scene(inputs[0]);
  }
  for (const std::string& p : inputs)
    if (is_scene(p)) throw InputError(command + ": '" + p + "': a scene file (.json) goes alone, not among meshes");
  return scene_from_meshes(inputs);
}

// One frame with every layer captured: the dump of `scene` under `opt` on `backend`.
// Dumps check the image stage: every ROI is peeled (Stage::image), whatever the router would do.
oracle::Dump capture_frame(const std::vector<Object>& objects, const DetectOptions& options, Runner& runner) {
  std::vector<CapturedView> captured;
  DetectOptions opt = options;
  opt.stage = Stage::image;
  runner.detector->capture_layers(&captured);
  FrameResult result;
  try {
    result = runner.detector->detect(objects, opt);
  } catch (...) {
    runner.detector->capture_layers(nullptr);
    throw;
  }
  runner.detector->capture_layers(nullptr);
  return oracle::make_dump(result, captured, objects, opt, runner.stage->renderer(), runner.stage->version(),
                           runner.backend(), runner.gl_settings());
}

// The broad phase's overlapping object pairs: the ROIs of a frame (before culling).
std::size_t count_overlapping_pairs(const std::vector<Object>& objects) {
  std::vector<Aabb> boxes;
  for (const Object& o : objects) boxes.push_back(bounds(o.mesh));
  return overlapping_pairs(boxes).size();
}

// ---- dynamic scenes and benchmarks ----

std::unique_ptr<Sequence> make_sequence(const std::string& name, std::size_t frames, bool rigid,
                                        std::size_t objects) {
  if (name == "test1") return make_test1(data_dir("fixtures/meshes"), frames, rigid);
  if (name == "test2") return make_test2(data_dir("fixtures/meshes"), frames, rigid);
  if (name == "crowd") return make_crowd(objects, frames, rigid);
  if (name == "cloth") return make_folding_cloth(40, frames, rigid);
  throw InputError("peelcd: unknown test scene \"" + name + "\" (expected test1, test2, crowd or cloth)");
}


// "K/N" (1 <= K <= N): which slice of a sharded run this is, as {K - 1, N}; {0, 1} when empty.
std::pair<std::size_t, std::size_t> parse_shard(const std::string& text, const std::string& what) {
  if (text.empty()) return {0, 1};
  std::size_t k = 0, n = 0;
  char slash = 0, rest = 0;
  if (std::sscanf(text.c_str(), "%zu%c%zu%c", &k, &slash, &n, &rest) != 3 || slash != '/' || k < 1 || n < 1 || k > n)
    throw InputError(what + " --shard \"" + text + "\": expected K/N with 1 <= K <= N, e.g. 2/8");
  return {k - 1, n};
}

CLI::Option* add_backend_option(CLI::App* c, std::string& backend, bool gl_only) {
  return c
      ->add_option("--backend", backend,
                   gl_only ? "GL backend: osmesa (software GL, the reference) or egl (a GPU, or Mesa without one)"
                           : "Image stage: osmesa (software GL, the reference), egl (a GPU, or Mesa without one) or "
                             "cpu (no GL)")
      ->capture_default_str();
}

// The options that shape a frame, shared by detect and dump (they override the scene file's).
// The frame's options, one flag per row of the option table (peelcd/core/options.h), and the
// GL stage's and the command line's own.
void add_frame_options(CLI::App* c, DetectArgs& d) {
  for (const OptionSpec& spec : option_table()) {
    if (!spec.flag) continue;
    if (spec.kind == OptionSpec::Kind::boolean) {
      c->add_flag(spec.flag, d.flags_on[spec.key], spec.help);
      c->add_flag(std::string("--no-") + (spec.flag + 2), d.flags_off[spec.key],
                  std::string("Turns ") + spec.flag + " off");
      continue;
    }
    std::string type = spec.kind == OptionSpec::Kind::choice ? "{" + std::string(spec.choices) + "}"
                       : spec.kind == OptionSpec::Kind::integer ? "INT" : "NUMBER";
    const auto g = [](double x) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.10g", x);
      return std::string(buf);
    };
    if (spec.kind != OptionSpec::Kind::choice && std::isfinite(spec.min))
      type += std::isfinite(spec.max) ? " in [" + g(spec.min) + ", " + g(spec.max) + "]" : " >= " + g(spec.min);
    // Stored as text, checked after parsing by the table (merged_options): one set of rules.
    c->add_option_function<std::string>(
         spec.flag, [&d, key = std::string(spec.key)](const std::string& v) { d.options[key] = v; }, spec.help)
        ->type_name(type);
  }
  add_gl_options(c, d.gl);
  c->add_option("--costs", d.costs, "The stage router's cost models from FILE (written by peelcd calibrate "
                                    "--write-costs on this backend and renderer; default: $PEELCD_COSTS, else the "
                                    "built-in models)")->check(CLI::ExistingFile);
  c->add_flag("--paper", d.paper,
              "The paper's configuration: point sampling, alternate peeling, paper IDs, constant epsilon, one view "
              "along world x, no culling (other options given override it)");
  add_backend_option(c, d.backend);
}


}  // namespace peelcd::cli
