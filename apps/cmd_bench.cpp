// peelcd bench (the command line; shared parts in cli.h).
#include "cli.h"
#include "peelcd/version.h"
#include "peelcd/bench/floor.h"
#include "peelcd/core/cpu_stage.h"
#include "peelcd/core/broad_phase.h"
#include "peelcd/core/aabb.h"

namespace peelcd::cli {

struct BenchArgs {
  std::string scene = "test1";  // test1, test2, crowd or a scene file
  std::size_t frames = 12;
  std::size_t objects = 200;  // crowd
  int res = 0;  // 0: the shared 512^2 budget, tiles by need (detect's default)
  std::string backend = kDefaultBackend;
  unsigned threads = 0;  // 0: the machine's (at most 8)
  std::string csv;
};

// Found, missed and false contacts of a peer against the exact pairs, object pair by object pair
// (the peers' broad phases may list pairs in another order, or more of them).
Score score_peer(const bench::PeerFrame& exact, const bench::PeerFrame& peer) {
  Score total;
  for (std::size_t i = 0; i < exact.objects.size(); ++i) {
    const auto it = std::lower_bound(peer.objects.begin(), peer.objects.end(), exact.objects[i]);
    static const std::vector<std::uint64_t> none;
    const std::vector<std::uint64_t>& got =
        it != peer.objects.end() && *it == exact.objects[i] ? peer.per_pair[std::size_t(it - peer.objects.begin())] : none;
    std::vector<std::uint64_t> common;
    std::set_intersection(exact.per_pair[i].begin(), exact.per_pair[i].end(), got.begin(), got.end(),
                          std::back_inserter(common));
    total.exact += exact.per_pair[i].size();
    total.found += common.size();
    total.missed += exact.per_pair[i].size() - common.size();
    total.false_contacts += got.size() - common.size();
  }
  // Pairs the peer reported that the exact broad phase does not list: all false.
  for (std::size_t j = 0; j < peer.objects.size(); ++j)
    if (!std::binary_search(exact.objects.begin(), exact.objects.end(), peer.objects[j]))
      total.false_contacts += peer.per_pair[j].size();
  return total;
}

int run_bench(const BenchArgs& a) {
  if (!a.csv.empty()) check_output_path(a.csv, "peelcd bench: --csv");
  std::unique_ptr<Sequence> seq;
  std::vector<Object> fixed;
  if (a.scene == "test1" || a.scene == "test2") {
    seq = make_sequence(a.scene, a.frames);
  } else if (a.scene == "crowd") {
    seq = make_crowd(a.objects, a.frames);
  } else {
    // A scene file's objects do not move: passed as rigid at the identity pose, so that every
    // method may keep what it builds from them (FCL its trees, the GL stage the shapes).
    fixed = load_objects(load_scene(a.scene));
    for (Object& o : fixed) o.rigid = RigidMotion{std::make_shared<const Mesh>(o.mesh), Eigen::Affine3d::Identity()};
  }
  const unsigned hw = std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
  const unsigned threads = a.threads ? a.threads : hw;
  // llvmpipe reads its thread count when the context is made: the same count as the peers. One
  // thread is LP_NUM_THREADS=0: llvmpipe rasterizes on the calling thread (with 1 it hands every
  // draw to one worker thread and waits for it: still one thread working, plus the handoff).
  if (a.threads) setenv("LP_NUM_THREADS", std::to_string(a.threads == 1 ? 0 : a.threads).c_str(), 1);
  gl::GlOptions gl_base;
  gl_base.workers = threads;
  Runner runner = make_runner(a.backend, gl_base);
  if (!runner.gl) throw InputError("peelcd bench: --backend cpu: the benchmark times GL stages (use osmesa or egl)");
  if (a.res > 0 && a.res > runner.stage->max_resolution())
    throw InputError("peelcd bench: --res " + std::to_string(a.res) + " is above GL_MAX_TEXTURE_SIZE");

  struct Config {
    std::string name;
    std::string column;  // its column in the per-phase table
    DetectOptions opt;
    gl::GlOptions gl;
  };
  std::vector<Config> configs;
  DetectOptions base;  // the default of detect: the router
  base.threads = threads;  // culling and the exact CPU path: the peers' thread count
  base.resolution = a.res;
  gl::GlOptions gpu_resolve = gl_base;
  gpu_resolve.resolve = Resolve::gpu;
  gl::GlOptions multi = gl_base;
  multi.peeler = Peeler::multipass;
  configs.push_back({"peelcd default (stage auto)", "default", base, gl_base});
  DetectOptions exact = base;
  exact.stage = Stage::exact;
  configs.push_back({"peelcd exact CPU path (no image)", "exact", exact, gl_base});
  DetectOptions image = base;
  image.stage = Stage::image;
  configs.push_back({"peelcd image stage (conservative)", "image", image, gl_base});
  DetectOptions box = image;
  box.cull = Cull::box;
  configs.push_back({"peelcd image stage, box culling", "box cull", box, gl_base});
  configs.push_back({"peelcd image stage, GPU resolve", "gpu rslv", image, gpu_resolve});
  DetectOptions half = image;  // half the tile side: the texels culling saves
  if (half.resolution > 0)
    half.resolution = std::max(16, half.resolution / 2);
  else
    half.budget = std::max(16, half.budget / 2);
  configs.push_back({"peelcd image stage, half resolution", "half res", half, gl_base});
  if (image.resolution == 0) {  // the conservative stage's earlier tiles: 12 texels per median edge
    DetectOptions fine = image;
    fine.edge_texels = kPointEdgeTexels;
    configs.push_back({"peelcd image stage, 12 texels per edge", "12 tx/edge", fine, gl_base});
  }
  // Point sampling (the paper's image stage, with this project's culling, views and slope
  // epsilon): the default of 0.2.0, three views along the world axes. Lossy: see the miss column.
  DetectOptions point = image;
  point.conservative = false;
  point.ids = IdMode::ring;
  point.theta = point.phi = point.roll = 0.0;
  point.views = 3;
  configs.push_back({"peelcd point sampling, 3 views", "point 3v", point, gl_base});
  configs.push_back({"peelcd point sampling, multi-pass", "multipass", point, multi});
  DetectOptions one = point;
  one.views = 1;
  configs.push_back({"peelcd point, 1 view, full peeling", "1v full", one, gl_base});
  DetectOptions paper = one;  // the paper's pipeline: the whole overlap box, one view
  paper.peel = PeelMode::alternate;
  paper.ids = IdMode::paper;
  paper.slope = 0.0;
  paper.cull = Cull::box;
  if (a.res == 0 && !seq) paper.resolution = 256;  // the paper's 256^2 on one pair (its Fig. 8)
  configs.push_back({"peelcd paper config", "paper", paper, gl_base});
  configs.push_back({"peelcd paper config, multi-pass", "paper mp", paper, multi});

  // The floors: one bare draw of every triangle touching the overlap box (the paper's ROI), and
  // of the triangles contact culling keeps (what the image-stage configurations draw).
  DetectOptions floor1 = point, cfloor1 = point;
  floor1.views = cfloor1.views = 1;
  floor1.cull = Cull::box;
  cfloor1.cull = Cull::contact;
  cfloor1.edge_texels = edge_texels_of(image);  // the conservative image stage's tiles
  const std::size_t cg = configs.size(), fr = cg + 1, fb = cg + 2, fl = cg + 3, cfl = cg + 4;
  const std::size_t methods = cg + 5;
  std::vector<std::string> names;
  for (const Config& c : configs) names.push_back(c.name);
  names.insert(names.end(), {"CGAL, cropped to the overlap box", "FCL 0.7, deforming refit",
                             "FCL 0.7, deforming rebuilt cropped", "floor: 1 bare draw, overlap box",
                             "floor: 1 bare draw, culled"});
  bench::FclPeer fcl_refit(bench::FclPeer::Deforming::refit, threads);
  bench::FclPeer fcl_rebuild(bench::FclPeer::Deforming::rebuild, threads);
  std::vector<FrameResult> results(configs.size());
  std::vector<std::vector<double>> ms(methods);
  std::vector<Score> scores(methods);
  std::vector<std::vector<std::vector<double>>> phase_ms;  // [phase][method] -> frame times
  if (seq) phase_ms.assign(seq->phases(), std::vector<std::vector<double>>(methods));
  std::string csv = "peelcd_version,frame,method,ms,nctp,found,false_contacts\n";
  std::vector<Object> objects;
  const std::size_t frames = seq ? seq->frames() : a.frames;
  // One untimed pass over the frames first: shader compilation, rigid shapes' uploads, FCL's
  // trees of rigid shapes and the growth of every buffer happen once, and would otherwise land
  // on whichever method meets them first. The timed pass is the steady state.
  for (std::size_t f = 0; f < (seq ? frames : std::min<std::size_t>(frames, 1)); ++f) {
    if (seq) seq->frame(f, objects);
    const std::vector<Object>& obj = seq ? objects : fixed;
    for (std::size_t c = 0; c < configs.size(); ++c) {
      runner.use(configs[c].gl);
      runner.detector->detect(obj, configs[c].opt, results[c]);
    }
    fcl_refit.frame(obj);
    fcl_rebuild.frame(obj);
  }
  std::size_t rois = 0, rois_routed_exact = 0;
  Progress progress;
  for (std::size_t f = 0; f < frames; ++f) {
    if (seq) seq->frame(f, objects);
    const std::vector<Object>& obj = seq ? objects : fixed;
    // Side by side on the same frame: the exact reference first (it is the CGAL peer).
    const bench::PeerFrame ref = bench::cgal_frame(obj, threads);
    std::vector<double> t(methods);
    std::vector<Score> s(methods);
    for (std::size_t c = 0; c < configs.size(); ++c) {
      runner.use(configs[c].gl);
      runner.detector->detect(obj, configs[c].opt, results[c]);
      t[c] = results[c].timings.total;
      s[c] = score_frame(results[c], ref);
    }
    rois += results[0].pairs.size();
    rois_routed_exact += results[0].rois_exact;
    t[cg] = ref.ms;
    s[cg] = Score{ref.pairs, ref.pairs, 0, 0};
    const bench::PeerFrame refit = fcl_refit.frame(obj);
    t[fr] = refit.ms;
    s[fr] = score_peer(ref, refit);
    const bench::PeerFrame rebuilt = fcl_rebuild.frame(obj);
    t[fb] = rebuilt.ms;
    s[fb] = score_peer(ref, rebuilt);
    runner.use(gl_base);
    t[fl] = bench::floor_ms(*runner.detector, *runner.gl, obj, floor1);
    t[cfl] = bench::floor_ms(*runner.detector, *runner.gl, obj, cfloor1);
    s[fl] = s[cfl] = Score{ref.pairs, 0, ref.pairs, 0};
    for (std::size_t m = 0; m < methods; ++m) {
      ms[m].push_back(t[m]);
      scores[m].exact += s[m].exact;
      scores[m].found += s[m].found;
      scores[m].missed += s[m].missed;
      scores[m].false_contacts += s[m].false_contacts;
      if (seq) phase_ms[seq->phase(f)][m].push_back(t[m]);
      char line[256];
      std::snprintf(line, sizeof line, "%s,%zu,\"%s\",%.4f,%zu,%zu,%zu\n", PEELCD_VERSION_STRING, f, names[m].c_str(), t[m],
                    s[m].exact, s[m].found, s[m].false_contacts);
      csv += line;
    }
    progress(f + 1, frames);
  }
  std::vector<double> med(methods);
  for (std::size_t m = 0; m < methods; ++m) med[m] = median(ms[m]);
  // The FCL ratio is against the faster of its two ways with deforming objects.
  const std::size_t fc = med[fr] <= med[fb] ? fr : fb;
  std::size_t tris = 0;
  for (const Object& o : (seq ? objects : fixed)) tris += o.mesh.triangles.size();
  std::printf("peelcd bench: %s, %zu frames, %zu objects, %zu triangles, %s, %s (%s), medians per frame after an untimed pass\n",
              a.scene.c_str(), frames, (seq ? objects : fixed).size(), tris,
              base.resolution ? (std::to_string(base.resolution) + "^2 per ROI").c_str()
                              : ("a " + std::to_string(base.budget) + "^2 budget shared by the ROIs").c_str(),
              runner.backend().c_str(), runner.renderer().c_str());
  const char* lp = std::getenv("LP_NUM_THREADS");
  std::printf("threads: CGAL and FCL %u (object pairs spread over them); peelcd host resolve %u lanes, llvmpipe %s, "
              "culling and exact CPU path %u, broad phase and the image stage's narrow phase 1\n",
              threads, threads, lp ? (std::string("LP_NUM_THREADS=") + lp).c_str() : "its default (one per core)", threads);
  std::printf("router (default row): %zu of %zu ROIs to the exact CPU path over the timed frames\n", rois_routed_exact, rois);
  std::printf("%-36s %10s %8s %7s %8s %8s %8s\n", "method", "median ms", "miss", "false", "x CGAL", "x FCL", "x floor");
  for (std::size_t m = 0; m < methods; ++m) {
    const bool is_floor = m >= fl;
    std::printf("%-36s %10.2f", names[m].c_str(), med[m]);
    if (is_floor) std::printf(" %8s %7s", "-", "-");
    else std::printf(" %7.2f%% %7zu", 100.0 * scores[m].miss_ratio(), scores[m].false_contacts);
    if (m < cg) {
      const std::size_t floor = configs[m].opt.cull == Cull::box ? fl : cfl;
      std::printf(" %8.2f %8.2f %8.2f\n", med[m] / med[cg], med[m] / med[fc], med[floor] > 0 ? med[m] / med[floor] : 0.0);
    } else {
      std::printf("\n");
    }
  }
  std::printf("(miss / false: over all frames against the exact pairs; FCL's triangle test is not exact; the floor finds nothing.\n"
              " x CGAL: against the cropped CGAL peer; x FCL: against the faster FCL row (%s); x floor: against one bare\n"
              " draw of the triangles the configuration would draw, one view. FCL trees kept: %zu (refit row), %zu (rebuilt\n"
              " row); refits %zu; cropped per-pair trees %zu and %zu, all frames.)\n",
              fc == fr ? "refit" : "rebuilt", fcl_refit.builds(), fcl_rebuild.builds(), fcl_refit.refits(),
              fcl_refit.pair_builds(), fcl_rebuild.pair_builds());
  if (seq && phase_ms.size() > 1) {
    std::printf("\nper phase, median ms:\n%-7s", "phase");
    for (const Config& c : configs) std::printf(" %9s", c.column.c_str());
    for (const char* peer : {"CGAL", "FCL refit", "FCL build", "floor", "cfloor"}) std::printf(" %9s", peer);
    std::printf(" %9s %9s\n", "dflt/CGAL", "dflt/FCL");
    for (std::size_t p = 0; p < phase_ms.size(); ++p) {
      std::printf("(%c)    ", char('a' + p));
      if (phase_ms[p][0].empty()) {  // fewer frames than phases
        std::printf(" no frames\n");
        continue;
      }
      std::vector<double> pm(methods);
      for (std::size_t m = 0; m < methods; ++m) std::printf(" %9.2f", pm[m] = median(phase_ms[p][m]));
      std::printf(" %9.2f %9.2f\n", pm[0] / pm[cg], pm[0] / std::min(pm[fr], pm[fb]));
    }
  }
  if (!a.csv.empty()) write_output(a.csv, csv);
  return 0;
}


std::vector<Command> add_bench_commands(CLI::App& app) {
  auto be_holder = std::make_shared<BenchArgs>();
  BenchArgs& be = *be_holder;
  CLI::App* benchmark = app.add_subcommand(
      "bench", "Time peelcd's configurations, CGAL (cropped to the overlap box), FCL 0.7 (rigid trees kept, "
               "deforming ones refitted or rebuilt, its own broad phase) and the bare-draw floor side by side on "
               "the same frames; print medians, miss ratios and ratios");
  benchmark->add_option("scene", be.scene, "test1, test2, crowd or a scene file")->capture_default_str();
  benchmark->add_option("--objects", be.objects, "Balls of the crowd scene")->check(CLI::Range(2, 5000))
      ->capture_default_str();
  benchmark->add_option("--threads", be.threads, "Threads of the peers, of peelcd's host resolve and of llvmpipe "
                                                 "(LP_NUM_THREADS); 0 = one per core, at most 8")
      ->check(CLI::Range(0, 64))->capture_default_str();
  benchmark->add_option("--frames", be.frames, "Frames (of the test scene; repeats of a scene file)")
      ->check(kPositive)->capture_default_str();
  benchmark->add_option("--res", be.res, "Texture size per ROI for peelcd; 0 = share the 512^2 budget with "
                                         "tiles by need, as detect does")->capture_default_str()
      ->check(kNonNegative);
  add_backend_option(benchmark, be.backend, true);
  benchmark->add_option("--csv", be.csv, "Write one row per (frame, method) to FILE, or - for stdout")->check(kOutputPath);

  return {{benchmark, [be_holder] { return run_bench(*be_holder); }}};
}
}  // namespace peelcd::cli
