// peelcd simulate (the command line; shared parts in cli.h).
#include "cli.h"
#include "peelcd/io/result_json.h"

namespace peelcd::cli {

// The paper's Tables 1 and 2 (GeForce 7900GTX): nCTP, AABB, GPU, readback, CPU, total per phase.
const std::vector<std::array<double, 6>>& paper_table(const std::string& name) {
  static const std::vector<std::array<double, 6>> t1 = {{15, 0.07, 3.11, 0.11, 0.07, 3.36},
                                                         {33, 0.07, 3.08, 0.13, 0.14, 3.42},
                                                         {96, 0.07, 3.28, 0.15, 0.44, 3.94},
                                                         {173, 0.07, 3.02, 0.36, 0.68, 4.13}};
  static const std::vector<std::array<double, 6>> t2 = {
      {16, 0.03, 2.66, 0.12, 0.10, 2.91},  {115, 0.03, 3.05, 0.68, 0.66, 4.42}, {96, 0.03, 4.26, 0.39, 0.48, 5.16},
      {39, 0.03, 2.39, 0.14, 0.36, 2.93},  {125, 0.03, 3.22, 0.73, 0.67, 4.65}, {222, 0.03, 2.38, 0.84, 0.95, 4.20},
      {339, 0.03, 3.15, 0.92, 1.66, 5.75}, {262, 0.03, 2.90, 0.71, 1.17, 4.81}};
  return name == "test1" ? t1 : t2;
}

struct SimArgs {
  std::string test;
  std::size_t frames = 40;
  std::size_t objects = 200;  // crowd
  bool no_rigid = false;
  DetectArgs detect;
  std::string csv;
};

int run_simulate(const SimArgs& a) {
  if (!a.csv.empty()) {
    check_output_path(a.csv, "peelcd simulate: --csv");
    refuse_overwriting_data(a.csv, "peelcd simulate: --csv");  // the built-in scenes' meshes
  }
  const auto seq = make_sequence(a.test, a.frames, !a.no_rigid, a.objects);
  Scene defaults;
  const DetectOptions opt = merged_options(defaults, a.detect);
  Runner runner = make_runner(a.detect.backend, merged_gl_options(Scene{}, a.detect.gl), a.detect.costs);
  std::vector<Object> objects;
  std::string csv = "frame,phase,triangles,rois,rois_exact,rois_peeled,triangles_uploaded,triangles_indexed,shape_uploads,gl_passes,pcs_readbacks,nctp,found,"
                    "false_contacts,aabb_ms,upload_ms,gpu_ms,readback_ms,cpu_ms,total_ms,gl_draws,gl_dispatches,gl_readbacks,"
                    "bytes_uploaded,bytes_read,geometry_bytes\n";
  std::printf("peelcd simulate %s: %zu frames, %s, ids=%s peel=%s slope=%g views=%d res=%s\n", seq->name().c_str(),
              seq->frames(), runner.renderer().c_str(), to_string(opt.ids), to_string(opt.peel), opt.slope,
              opt.views, opt.resolution ? std::to_string(opt.resolution).c_str() : ("budget " + std::to_string(opt.budget)).c_str());
  std::printf("%5s %5s %7s %5s %5s %6s %8s %8s %6s %6s %5s %6s %6s %6s %5s %7s %8s %8s %8s %8s\n", "frame", "phase",
              "tris", "ROIs", "exact", "peeled", "uploaded", "indexed", "shapes", "passes", "reads", "nCTP", "found", "miss%",
              "false", "aabb", "gpu", "readback", "cpu", "total");
  struct PhaseSum {
    std::size_t frames = 0;
    double nctp = 0, found = 0, aabb = 0, gpu = 0, readback = 0, cpu = 0, total = 0;
  };
  std::vector<PhaseSum> phases(seq->phases());
  std::size_t false_total = 0;
  double gl_sum[6] = {0, 0, 0, 0, 0, 0};  // draws, dispatches, readbacks, bytes up, bytes read, geometry bytes
  double gl_after_first = 0;  // geometry bytes uploaded after the first frame
  FrameResult r;  // reused frame after frame, as an application would
  const Progress progress("frames", true);
  for (std::size_t f = 0; f < seq->frames(); ++f) {
    progress(f, seq->frames());
    seq->frame(f, objects);
    if (opt.self)  // --self: every object's self pairs, scored too
      for (Object& o : objects) o.self = true;
    runner.detector->detect(objects, opt, r);
    const bench::PeerFrame exact = bench::cgal_frame(objects);
    const Score sc = score_frame(r, exact);
    false_total += sc.false_contacts;
    std::size_t tris = 0;
    for (const Object& o : objects) tris += o.mesh.triangles.size();
    const Timings& t = r.timings;
    const int ph = seq->phase(f);
    std::printf("%5zu %5c %7zu %5zu %5zu %6zu %8zu %8zu %6zu %6zu %5zu %6zu %6zu %5.1f%% %5zu %7.3f %8.2f %8.3f %8.2f %8.2f\n",
                f, char('a' + ph), tris, r.pairs.size(), r.rois_exact, r.rois_peeled, r.triangles_uploaded, r.triangles_indexed,
                r.shape_uploads, r.gl_passes, r.pcs_readbacks, sc.exact, sc.found, 100.0 * sc.miss_ratio(), sc.false_contacts, t.aabb,
                t.upload + t.gpu, t.readback, t.cpu, t.total);
    char line[512];
    std::snprintf(line, sizeof line,
                  "%zu,%c,%zu,%zu,%zu,%zu,%zu,%zu,%zu,%zu,%zu,%zu,%zu,%zu,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%zu,%zu,%zu,%zu,%zu,%zu\n", f,
                  char('a' + ph), tris, r.pairs.size(), r.rois_exact, r.rois_peeled, r.triangles_uploaded, r.triangles_indexed,
                  r.shape_uploads, r.gl_passes,
                  r.pcs_readbacks, sc.exact, sc.found, sc.false_contacts, t.aabb, t.upload, t.gpu, t.readback, t.cpu,
                  t.total, r.gl_draws, r.gl_dispatches, r.gl_readbacks, r.bytes_uploaded, r.bytes_read, r.geometry_bytes);
    gl_sum[0] += double(r.gl_draws);
    gl_sum[1] += double(r.gl_dispatches);
    gl_sum[2] += double(r.gl_readbacks);
    gl_sum[3] += double(r.bytes_uploaded);
    gl_sum[4] += double(r.bytes_read);
    gl_sum[5] += double(r.geometry_bytes);
    if (f > 0) gl_after_first += double(r.geometry_bytes);
    csv += line;
    PhaseSum& p = phases[ph];
    ++p.frames;
    p.nctp += double(sc.exact);
    p.found += double(sc.found);
    p.aabb += t.aabb;
    p.gpu += t.upload + t.gpu;
    p.readback += t.readback;
    p.cpu += t.cpu;
    p.total += t.total;
  }
  progress(seq->frames(), seq->frames());
  const bool paper_scene = seq->name() == "test1" || seq->name() == "test2";
  std::printf(paper_scene ? "\nsummary (means per phase; the paper's table beside, GeForce 7900GTX; ms)\n"
                          : "\nsummary (means; ms)\n");
  std::printf("%5s | %6s %6s %6s %7s %8s %7s %8s", "", "nCTP", "found", "AABB", "GPU", "readback", "CPU", "total");
  if (paper_scene) std::printf(" | %6s %6s %6s %8s %6s %6s", "nCTP", "AABB", "GPU", "readback", "CPU", "total");
  std::printf("\n");
  for (std::size_t i = 0; i < phases.size(); ++i) {
    const PhaseSum& p = phases[i];
    const double n = std::max<double>(1, double(p.frames));
    std::printf("(%c)   | %6.0f %6.0f %6.3f %7.2f %8.3f %7.2f %8.2f", char('a' + i), p.nctp / n, p.found / n, p.aabb / n,
                p.gpu / n, p.readback / n, p.cpu / n, p.total / n);
    if (paper_scene) {
      const auto& paper = paper_table(seq->name());
      std::printf(" | %6.0f %6.2f %6.2f %8.2f %6.2f %6.2f", paper[i][0], paper[i][1], paper[i][2], paper[i][3], paper[i][4],
                  paper[i][5]);
    }
    std::printf("\n");
  }
  std::printf("false contacts over all frames: %zu\n", false_total);
  const double nf = double(std::max<std::size_t>(seq->frames(), 1));
  std::printf("GL per frame (means): %.1f draws, %.1f dispatches, %.1f readbacks, %.1f KB uploaded (%.1f KB of it mesh "
              "data; %.1f KB after the first frame), %.1f KB read back\n",
              gl_sum[0] / nf, gl_sum[1] / nf, gl_sum[2] / nf, gl_sum[3] / nf / 1024.0, gl_sum[5] / nf / 1024.0,
              seq->frames() > 1 ? gl_after_first / (nf - 1.0) / 1024.0 : 0.0, gl_sum[4] / nf / 1024.0);
  if (!a.csv.empty()) write_output(a.csv, csv);
  return false_total ? 1 : 0;
}


std::vector<Command> add_simulate_commands(CLI::App& app) {
  auto si_holder = std::make_shared<SimArgs>();
  SimArgs& si = *si_holder;
  CLI::App* simulate = app.add_subcommand(
      "simulate", "Run the paper's dynamic scenes (test1: a walking raptor among 40 billiard balls; test2: a "
                  "tearing cloth with 40 falling objects; and a pile of balls and a folding cloth) and print per-frame nCTP, counters and stage times, "
                  "and a summary per phase beside the paper's Tables 1 and 2");
  simulate->add_option("test", si.test, "test1, test2, crowd (a pile of --objects balls in light contact) or cloth (a "
                                       "9,600-triangle cloth folding through itself onto a ball: self-collision)")
      ->required()->check(CLI::IsMember({"test1", "test2", "crowd", "cloth"}));
  simulate->add_option("--objects", si.objects, "Balls of the crowd scene")->check(CLI::Range(2, 5000))
      ->capture_default_str();
  simulate->add_option("--frames", si.frames, "Frames")->check(kPositive)->capture_default_str();
  add_frame_options(simulate, si.detect);
  simulate->add_flag("--no-rigid", si.no_rigid, "Pass the rigid objects as plain triangles (no shape caching)");
  simulate->add_option("--csv", si.csv, "Write one row per frame to FILE, or - for stdout")->check(kOutputPath);

  return {{simulate, [si_holder] { return run_simulate(*si_holder); }}};
}
}  // namespace peelcd::cli
