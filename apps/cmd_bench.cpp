// peelcd bench (the command line; shared parts in cli.h).
#include "cli.h"
#include "peelcd/version.h"
#include "peelcd/bench/self_bench.h"
#include "peelcd/bench/suite.h"
#include "peelcd/bench/volume_bench.h"
#include "peelcd/bench/query_bench.h"
#include "peelcd/eval/classes.h"
#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/broad_phase.h"
#include "peelcd/core/aabb.h"

namespace peelcd::cli {

struct BenchArgs {
  std::string scene = "test1";  // test1, test2, crowd, spheres, spheres-wave, a scene file
  std::size_t frames = 12;
  std::size_t objects = 200;  // crowd
  int stacks = 288;           // spheres: 330,624 triangles each (570: 1,297,320)
  int cloth = 0;              // cloth-self: 6 n^2 triangles (0: 130, 101,400); cloth-crumpled: 2 n^2 (0: 224, 100,352)
  int res = 0;  // 0: the shared 512^2 budget, tiles by need (detect's default)
  std::string backend = kDefaultBackend;
  unsigned threads = 0;  // 0: the machine's (at most 8)
  unsigned scaling = 0;  // > 0: the default World row again with this many threads
  bool time_routes = false;  // World::time_routes(true) for the World rows (else unset)
  bool short_rows = false;
  bool audit = false;
  bool no_gpu_timers = false;
  bool return_memory = false;
  std::string csv;
  std::map<std::string, std::string> gl;  // GL stage options (gl_option_table() rows by key)
};

// `bench depth` and `bench distance`: the queries' scenes and tables (peelcd/bench/query_bench.h).
int run_query_bench(const BenchArgs& a) {
  bench::QuerySuite q;
  q.frames = a.frames;
  const std::string meshes = data_dir("fixtures/meshes") + "/";
  if (a.scene == "depth") {
    for (const DepthClass& c : depth_classes())
      q.scenes.push_back({c.scene.name, c.scene.objects[0].mesh, c.scene.objects[1].mesh});
    Mesh dragon = load_mesh(meshes + "dragon_3k.obj");  // the bunny and the dragon crossing deeply
    for (Vec3& v : dragon.vertices) v += Vec3(0.1, 0.05, 0.0);
    q.scenes.push_back({"bunny x dragon", load_mesh(meshes + "bunny_3k.obj"), dragon});
  } else {
    const Mesh box = box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1));
    q.scenes.push_back({"boxes 1e-4 apart", box, box_mesh(Vec3(1.0001, 0.2, 0.3), Vec3(2, 0.9, 1.5))});
    q.scenes.push_back({"spheres 0.01 apart", uv_sphere(Vec3(0, 0, 0), 1.0, 96, 48), uv_sphere(Vec3(2.01, 0.0, 0.0), 1.0, 96, 48)});
    Mesh kitten = load_mesh(meshes + "kitten_1k5.obj");
    const Mesh fish = load_mesh(meshes + "fish_2k.obj");
    // The kitten moved off the fish along x: its box 0.01 of the fish's size beyond the fish's.
    const Aabb bf = bounds(fish), bk = bounds(kitten);
    for (Vec3& v : kitten.vertices) v += Vec3(bf.hi.x() - bk.lo.x() + 0.01 * bf.extent().maxCoeff(), 0.0, 0.0);
    q.scenes.push_back({"kitten near fish", kitten, fish});
  }
  const std::string csv = a.scene == "depth" ? bench::run_depth_suite(q) : bench::run_distance_suite(q);
  if (!a.csv.empty()) write_output(a.csv, csv);
  return 0;
}

int run_bench(const BenchArgs& a) {
  if (!a.csv.empty()) {
    check_output_path(a.csv, "peelcd bench: --csv");
    refuse_overwriting_data(a.csv, "peelcd bench: --csv");  // the built-in scenes' meshes
    const bool builtin = a.scene == "volume" || a.scene == "depth" || a.scene == "distance" || a.scene == "cloth-self" || a.scene == "cloth-crumpled" || a.scene == "spheres" ||
                         a.scene == "spheres-wave" || a.scene == "test1" || a.scene == "test2" || a.scene == "crowd";
    if (!builtin) refuse_overwriting_input(a.csv, scene_inputs(load_scene(a.scene)), "peelcd bench: --csv");
  }
  if (a.scaling && (a.scene == "volume" || a.scene == "depth" || a.scene == "distance"))
    throw InputError("peelcd bench: --scaling times the World rows of the pair and self scenes, not " + a.scene);
  if (a.scene == "volume") {  // intersection volume: its own table (peelcd/bench/volume_bench.h)
    bench::VolumeSuite v;
    v.frames = a.frames;
    // The error estimate's coverage on the closed fixtures, in a ring (the last against the first).
    for (const char* name : {"kitten_1k5", "fish_2k", "torus", "dragon_3k", "bunny_3k", "velociraptor", "kitten_1k5"})
      v.coverage_meshes.emplace_back(name, load_mesh(data_dir("fixtures/meshes") + "/" + name + ".obj"));
    v.coverage_frames = 20 * a.frames;
    const std::string csv = bench::run_volume_suite(v);
    if (!a.csv.empty()) write_output(a.csv, csv);
    return 0;
  }
  if (a.scene == "depth" || a.scene == "distance") return run_query_bench(a);
  if (a.scene == "cloth-self" || a.scene == "cloth-crumpled") {  // self-collision: its own table (peelcd/bench/self_bench.h)
    if (a.threads) setenv("LP_NUM_THREADS", std::to_string(a.threads == 1 ? 0 : a.threads).c_str(), 1);
    bench::SelfSuite self;
    self.crumpled = a.scene == "cloth-crumpled";
    self.n = a.cloth ? a.cloth : self.crumpled ? 224 : 130;
    self.frames = a.frames;
    self.audit = a.audit;
    self.scaling = a.scaling;
    self.stage = make_image_stage(a.backend, gl::GlOptions{});
    const std::string csv = bench::run_self_suite(self);
    if (!a.csv.empty()) write_output(a.csv, csv);
    return 0;
  }
  std::unique_ptr<Sequence> seq;
  std::vector<Object> fixed;
  bench::Suite suite;
  suite.scene = a.scene;
  if (a.scene == "spheres" || a.scene == "spheres-wave") {
    seq = make_crossing_spheres(a.stacks, a.frames, a.scene == "spheres-wave");
    suite.scene += " (" + std::to_string(4 * a.stacks * (a.stacks - 1)) + " triangles each)";
  } else if (a.scene == "test1" || a.scene == "test2" || a.scene == "crowd") {
    seq = make_sequence(a.scene, a.frames, true, a.objects);
  } else {
    // A scene file's objects do not move: passed as rigid at the identity pose, so that every
    // method may keep what it builds from them (FCL and the World their trees, the GL stage the
    // shapes).
    fixed = load_objects(load_scene(a.scene));
    for (Object& o : fixed) o.rigid = RigidMotion{std::make_shared<const Mesh>(o.mesh), Eigen::Affine3d::Identity()};
  }
  const unsigned hw = std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
  const unsigned threads = a.threads ? a.threads : hw;
  // llvmpipe reads its thread count when the context is made: the same count as the peers. One
  // thread is LP_NUM_THREADS=0: llvmpipe rasterizes on the calling thread (with 1 it hands every
  // draw to one worker thread and waits for it: still one thread working, plus the handoff).
  if (a.threads) setenv("LP_NUM_THREADS", std::to_string(a.threads == 1 ? 0 : a.threads).c_str(), 1);
  gl::GlOptions gl_base = merged_gl_options(Scene{}, a.gl);
  gl_base.workers = threads;
  if (a.backend == "cpu") throw InputError("peelcd bench: --backend cpu: the benchmark times GL stages (use osmesa or egl)");
  suite.stage = make_image_stage(a.backend, gl_base);
  suite.frames = seq ? seq->frames() : a.frames;
  suite.phases = seq ? seq->phases() : 1;
  if (seq) suite.phase = [&](std::size_t f) { return seq->phase(f); };
  suite.frame = [&](std::size_t f, std::vector<Object>& objects) {
    if (seq)
      seq->frame(f, objects);
    else if (objects.size() != fixed.size())
      objects = fixed;
  };
  suite.res = a.res;
  suite.threads = threads;
  suite.scaling_threads = a.scaling;
  if (a.time_routes) suite.time_routes = true;
  suite.short_rows = a.short_rows;
  suite.audit = a.audit;
  suite.gpu_timers = !a.no_gpu_timers;
  suite.keep_freed_memory = !a.return_memory;
  const Progress progress;
  suite.progress = [&](std::size_t done, std::size_t total) { progress(done, total); };
  std::string csv;
  try {
    csv = bench::run_suite(suite);
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
  if (!a.csv.empty()) write_output(a.csv, csv);
  return 0;
}

std::vector<Command> add_bench_commands(CLI::App& app) {
  auto be_holder = std::make_shared<BenchArgs>();
  BenchArgs& be = *be_holder;
  CLI::App* benchmark = app.add_subcommand(
      "bench", "Time peelcd's configurations (persistent bodies and the frame API), CGAL (cropped to the overlap box), FCL 0.7 (rigid trees kept, "
               "deforming ones refitted or rebuilt, its own broad phase), Embree 3 rtcCollide and Bullet 3 GImpact (float "
               "triangle tests) and the bare-draw floor side by side on "
               "the same frames; print medians, miss ratios and ratios");
  benchmark->add_option("scene", be.scene, "test1, test2, crowd, spheres (two crossing rigid spheres), spheres-wave "
                                           "(the same, a wave over their vertices every frame), cloth-self (self-collision of a folding "
                                           "cloth, one thread), cloth-crumpled (self-collision of a 100k-triangle cloth crumpled "
                                           "over a ball, one thread), volume (the intersection volume of two 99k-triangle "
                                           "spheres against CGAL), depth (the penetration depth against bisection), "
                                           "distance (the least distance against FCL's) or a scene file")
      ->capture_default_str();
  benchmark->add_option("--stacks", be.stacks, "spheres: latitude bands (4 s (s - 1) triangles a sphere: 288 -> 330,624, "
                                               "570 -> 1,297,320)")
      ->check(CLI::Range(3, 2000))->capture_default_str();
  benchmark->add_option("--cloth", be.cloth, "cloth-self: the cloth's resolution n (6 n^2 triangles; default 130 -> 101,400); "
                                             "cloth-crumpled: n (2 n^2 triangles; default 224 -> 100,352)")
      ->check(CLI::Range(2, 2000));
  benchmark->add_flag("--short", be.short_rows, "Only the World rows, the frame API's router and image stage, the peers "
                                                 "and the floors (for the scale scenes)");
  benchmark->add_flag("--audit", be.audit,
                      "Add FCL, Embree and Bullet each as a plain user writes it from its documentation "
                      "(bench/plain_fcl.cpp, plain_embree.cpp, plain_bullet.cpp) and print each peer row's ratio to its "
                      "library's (cloth-self, cloth-crumpled: Embree's self rows against its plain setup)");
  benchmark->add_flag("--no-gpu-timers", be.no_gpu_timers,
                      "No GL timer queries around the image stage's passes (the image-work table's raster, compute "
                      "and transfer columns; on by default)");
  benchmark->add_flag("--return-memory", be.return_memory,
                      "Leave glibc's allocator as it is (by default the bench keeps freed memory in the process, so "
                      "that one method's frees do not slow the next method's frame; docs/performance.md; "
                      "cloth-self and volume never change it)");
  benchmark->add_option("--objects", be.objects, "Balls of the crowd scene")->check(CLI::Range(2, 5000))
      ->capture_default_str();
  benchmark->add_option("--threads", be.threads, "Threads of the peers, of peelcd's host resolve and of llvmpipe "
                                                 "(LP_NUM_THREADS); 0 = one per core, at most 8")
      ->check(CLI::Range(0, 64))->capture_default_str();
  benchmark->add_option("--scaling", be.scaling, "Time the default World row again with N threads, side by side with "
                                                  "the others on the same frames, then the two World rows alone over the "
                                                  "frames, alternating, and print the ratio of each; with --threads 1, "
                                                  "also the ratio the work's balance alone allows N lanes (the lane model); "
                                                  "cloth-self, cloth-crumpled: the World's default and the frame API's "
                                                  "exact path on N threads against one, each two alone, alternating")
      ->check(CLI::Range(1, 64));
  benchmark->add_flag("--time-routes", be.time_routes,
                      "Time the World's two routes under stage auto on any stage (World::time_routes(true)); by "
                      "default they are timed where the stage runs on a GPU, and only on the resident image route "
                      "(batched: a GPU, or --resolve gpu)");
  benchmark->add_option("--frames", be.frames, "Frames (of the test scene; repeats of a scene file)")
      ->check(kPositive)->capture_default_str();
  benchmark->add_option("--res", be.res, "Texture size per ROI for peelcd; 0 = share the 512^2 budget with "
                                         "tiles by need, as detect does")->capture_default_str()
      ->check(kNonNegative);
  add_backend_option(benchmark, be.backend, true);
  add_gl_options(benchmark, be.gl, {"resolve", "gpu_filter", "coverage"});
  benchmark->add_option("--csv", be.csv, "Write one row per (frame, method) to FILE, or - for stdout")->check(kOutputPath);

  return {{benchmark, [be_holder] { return run_bench(*be_holder); }}};
}
}  // namespace peelcd::cli
