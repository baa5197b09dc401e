// peelcd: image-space collision detection through alternate surface peeling.
#include "core/reference.h"
#include "gl/pipeline.h"
#include "gl_osmesa/osmesa_context.h"
#include "io/error.h"
#include "io/result_json.h"
#include "io/scene.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

namespace {

using namespace peelcd;

constexpr int kExitBadInput = 2;

struct DetectArgs {
  std::string scene;
  int res = 0;  // 0 = not given
  std::string ids, peel;
  double slope = NAN;
  double theta = NAN, phi = NAN, epsilon = NAN;
  std::string json_out;
  int repeat = 1;
  bool check = false;
  bool quiet = false;
};

// Command-line values override the scene file's.
DetectOptions merged_options(const Scene& scene, const DetectArgs& a) {
  DetectOptions o = scene.options;
  if (a.res > 0) o.resolution = a.res;
  if (!a.ids.empty()) {
    const auto m = parse_id_mode(a.ids);
    if (!m) throw InputError("peelcd detect: --ids: unknown ID mode \"" + a.ids + "\" (expected paper or unique)");
    o.ids = *m;
  }
  if (!a.peel.empty()) {
    const auto m = parse_peel_mode(a.peel);
    if (!m) throw InputError("peelcd detect: --peel: unknown peel mode \"" + a.peel + "\" (expected full or alternate)");
    o.peel = *m;
  }
  if (!std::isnan(a.slope)) o.slope = a.slope;
  if (!std::isnan(a.theta)) o.theta = a.theta;
  if (!std::isnan(a.phi)) o.phi = a.phi;
  if (!std::isnan(a.epsilon)) o.epsilon = a.epsilon;
  return o;
}

// Writes `text` to `path` through a temporary file and a rename, so a failure never leaves a
// half-written file behind. "-" is stdout.
void write_output(const std::string& path, const std::string& text) {
  if (path == "-") {
    std::cout << text << "\n";
    return;
  }
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out) throw InputError("peelcd: cannot write '" + path + "'");
    out << text << "\n";
    if (!out.flush()) {
      std::remove(tmp.c_str());
      throw InputError("peelcd: cannot write '" + path + "'");
    }
  }
  std::filesystem::rename(tmp, path);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

int run_detect(const DetectArgs& a) {
  const Scene scene = load_scene(a.scene);
  const DetectOptions opt = merged_options(scene, a);
  const std::vector<Object> objects = load_objects(scene);

  gl::OsmesaContext context;
  gl::Pipeline pipeline(context);
  FrameResult result;
  std::vector<Timings> runs;
  for (int i = 0; i < std::max(1, a.repeat); ++i) {
    result = pipeline.detect(objects, opt);
    runs.push_back(result.timings);
  }
  if (runs.size() > 1) {  // report per-stage medians over the repeated frames
    const auto med = [&](double Timings::*f) {
      std::vector<double> v;
      for (const Timings& t : runs) v.push_back(t.*f);
      return median(v);
    };
    result.timings = {med(&Timings::aabb), med(&Timings::upload), med(&Timings::gpu),
                      med(&Timings::readback), med(&Timings::cpu), med(&Timings::total)};
  }

  if (!a.quiet) {
    std::printf("peelcd detect: %s  (%zu objects, %s)\n", a.scene.c_str(), objects.size(), result.renderer.c_str());
    std::printf("view theta=%g phi=%g  ids=%s  peel=%s  slope=%g\n", opt.theta, opt.phi, to_string(opt.ids),
                to_string(opt.peel), opt.slope);
    if (result.pairs.empty()) std::printf("no overlapping bounding boxes: no GL work\n");
    for (const PairResult& p : result.pairs) {
      std::printf("%s x %s: ROI %dx%d, eps %.3g, drawn %zu+%zu tris, %d layers, %zu PCS, %zu candidates, %zu colliding\n",
                  objects[p.object_a].name.c_str(), objects[p.object_b].name.c_str(), p.resolution,
                  p.resolution, p.epsilon, p.triangles_drawn_a, p.triangles_drawn_b, p.layers,
                  p.pcs_count, p.candidates, p.colliding.size());
      std::string line = " ";
      for (const Contact& c : p.colliding) {
        line += " (" + std::to_string(c.tri_a) + "," + std::to_string(c.tri_b) + ")";
        if (line.size() > 90) {
          std::printf("%s\n", line.c_str());
          line = " ";
        }
      }
      if (line.size() > 1) std::printf("%s\n", line.c_str());
      if (a.check) {
        const auto exact = exact_colliding_pairs(objects[p.object_a].mesh, objects[p.object_b].mesh);
        std::size_t found = 0, false_contacts = 0;
        for (const Contact& c : p.colliding)
          (std::binary_search(exact.begin(), exact.end(), pack_pair(c.tri_a, c.tri_b)) ? found : false_contacts)++;
        std::printf("  exact reference: %zu pairs; found %zu, missed %zu (miss ratio %.2f%%), false contacts %zu\n",
                    exact.size(), found, exact.size() - found,
                    exact.empty() ? 0.0 : 100.0 * double(exact.size() - found) / double(exact.size()),
                    false_contacts);
      }
    }
    const Timings& t = result.timings;
    std::printf("timings (ms%s): aabb %.3f  upload %.3f  gpu %.3f  readback %.3f  cpu %.3f  total %.3f\n",
                runs.size() > 1 ? (", median of " + std::to_string(runs.size())).c_str() : "",
                t.aabb, t.upload, t.gpu, t.readback, t.cpu, t.total);
  }
  if (!a.json_out.empty()) write_output(a.json_out, to_json(result, objects, opt).dump(2));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"peelcd: image-space collision detection between triangle meshes through "
               "alternate surface peeling (OSMesa reference backend)"};
  app.require_subcommand(1);
  DetectArgs d;
  CLI::App* detect = app.add_subcommand(
      "detect", "Run one frame of collision detection on a scene file and report the colliding "
                "triangle pairs (indices in each mesh file's triangle order)");
  detect->add_option("scene", d.scene, "Scene JSON file")->required();
  detect->add_option("--res", d.res, "Forced N x N texture per ROI (default: share a 512^2 budget)")
      ->check(CLI::PositiveNumber);
  detect->add_option("--ids", d.ids, "Triangle ID mode: paper (last-vertex IDs, T(v) sets) or unique");
  detect->add_option("--peel", d.peel, "Peel mode: full (every surface, default) or alternate (the paper's)");
  detect->add_option("--slope", d.slope, "Slope-following epsilon, in texels (default 1; 0 = the paper's constant epsilon)")
      ->check(CLI::NonNegativeNumber);
  detect->add_option("--theta", d.theta, "View longitude, degrees");
  detect->add_option("--phi", d.phi, "View latitude, degrees, in [-90, 90]")->check(CLI::Range(-90.0, 90.0));
  detect->add_option("--epsilon", d.epsilon, "PCS depth threshold in world units (default: one texel)")
      ->check(CLI::PositiveNumber);
  detect->add_option("--json", d.json_out, "Write the JSON report to FILE, or - for stdout");
  detect->add_option("--repeat", d.repeat, "Run the frame N times and report median timings")
      ->check(CLI::PositiveNumber);
  detect->add_flag("--check", d.check, "Also run the exact all-pairs reference and print the miss ratio");
  detect->add_flag("--quiet", d.quiet, "No human summary");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kExitBadInput;
  }
  try {
    if (*detect) return run_detect(d);
  } catch (const InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitBadInput;
  } catch (const gl::GlError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: internal: %s\n", e.what());
    return 1;
  }
  return 0;
}
