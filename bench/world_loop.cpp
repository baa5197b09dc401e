// peelcd_world_loop: the World alone on a scene file, frame after frame, for profilers and for
// the question the bench's turns cannot answer: what a frame costs with its data in cache
// (frames back to back) and with it evicted (--cold: 64 MB written between frames, as other
// work between two frames of a program would; --busy: a sort of 200k random integers between
// frames besides, which also leaves the branch predictors trained on other code, as the bench's
// other methods leave them: the bench's World frame costs what a --busy one does). A scene
// file's objects are rigid bodies at their file poses, brought to each frame by set_pose() as
// `peelcd bench` brings them; `--spheres S` takes `peelcd bench spheres --stacks S` instead
// (two crossing rigid spheres, turning: the posed traversal), its frames over and over; `--crowd N`
// the pile of `peelcd bench crowd --objects N` (rigid balls by set_pose, every fifth ball deforming
// by set_vertices); `--wave S` `peelcd bench spheres-wave --stacks S` (the spheres deforming:
// set_vertices and refits); `--cloth N` the crumpled cloth of `peelcd bench cloth-crumpled
// --cloth N` (2 N^2 triangles, one deforming body colliding with itself, its 6 frames over and
// over: refits, rebuilds and the self traversal). One thread, or `--threads T` (DetectOptions::threads). `--image`:
// every pair on the resident image route (Stage::image) of the GL stage on EGL with the GPU's
// resolve and the compute coverage, as `peelcd bench ... --backend egl --resolve gpu --coverage
// compute` times its "World, image stage" row; it also prints the host steps around the stage
// (for profiling the host work of the image route; on llvmpipe the stage's own work is the CPU's).
// `--model L`: the World's lane model (World::model_lanes): each frame planned for L lanes, run
// on one thread with its loops' items timed; prints what L lanes would take by the work's
// balance alone, and each loop's items, work, longest item and span (medians over the frames):
// where the scaling of a frame is lost to uneven work, measurable on a machine with few cores.
//
//   peelcd_world_loop SCENE|--spheres STACKS|--wave STACKS|--crowd N|--cloth N [--frames N] [--threads T] [--pairs] [--cold] [--busy] [--image] [--model L] [--warmup N]
//
// `--warmup N`: N frames first, untimed (the first frames grow the World's buffers and the
// stage's: on the image route they take up to twice a later frame's exact step).
// Prints the median frame (and its first quartile), the World's boxes and exact steps
// (Timings::aabb, Timings::cpu) and the contacts found. Under valgrind --tool=callgrind, the
// difference of two runs with different --frames is the instructions of that many frames.
#include "peelcd/backends.h"
#include "peelcd/core/primitives.h"
#include "peelcd/core/world/world.h"
#include "peelcd/eval/scenes.h"
#include "peelcd/io/scene.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

using namespace peelcd;

namespace {

double median(std::vector<double> v, double q = 0.5) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[std::size_t(double(v.size() - 1) * q)];
}

int usage(const char* why) {
  std::fprintf(stderr, "peelcd_world_loop: %s\nusage: peelcd_world_loop SCENE|--spheres STACKS|--wave STACKS|--crowd N|--cloth N [--frames N] [--threads T] "
               "[--pairs] [--cold] [--busy] [--image] [--model L] [--warmup N]\n",
               why);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string path;
  long frames = 300, stacks = 0, wave = 0, crowd = 0, cloth = 0, threads = 1, model = 0, warmup = 0;
  bool pairs = false, cold = false, busy = false, image = false;
  struct Count {
    const char* flag;
    long* value;
    long lo, hi;
    const char* what;
  };
  const Count counts[] = {{"--frames", &frames, 1, 10000000, "a count from 1 to 10,000,000"},
                          {"--spheres", &stacks, 3, 2000, "latitude bands from 3 to 2,000"},
                          {"--wave", &wave, 3, 2000, "latitude bands from 3 to 2,000"},
                          {"--crowd", &crowd, 2, 5000, "balls from 2 to 5,000"},
                          {"--cloth", &cloth, 2, 1000, "the cloth's resolution from 2 to 1,000"},
                          {"--threads", &threads, 0, 64, "0 (one per core) to 64"},
                          {"--model", &model, 2, 256, "lanes from 2 to 256"},
                          {"--warmup", &warmup, 0, 1000, "a count from 0 to 1,000"}};
  const auto count_option = [&](const char* arg) -> const Count* {
    for (const Count& c : counts)
      if (!std::strcmp(arg, c.flag)) return &c;
    return nullptr;
  };
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--pairs")) {
      pairs = true;
    } else if (!std::strcmp(argv[i], "--cold")) {
      cold = true;
    } else if (!std::strcmp(argv[i], "--image")) {
      image = true;
    } else if (!std::strcmp(argv[i], "--busy")) {
      busy = cold = true;
    } else if (const Count* c = count_option(argv[i])) {
      char* end = nullptr;
      const long n = i + 1 < argc ? std::strtol(argv[++i], &end, 10) : 0;
      if (!end || *end != '\0' || n < c->lo || n > c->hi) return usage((std::string(c->flag) + ": " + c->what).c_str());
      *c->value = n;
    } else if (path.empty() && argv[i][0] != '-') {
      path = argv[i];
    } else {
      return usage((std::string("unknown argument '") + argv[i] + "'").c_str());
    }
  }
  if (int(!path.empty()) + int(stacks != 0) + int(wave != 0) + int(crowd != 0) + int(cloth != 0) != 1)
    return usage("a scene file, --spheres, --wave, --crowd or --cloth, one of them");
  try {
    // The frames: a scene file's one frame (its objects as rigid shapes at the identity), or
    // the spheres' sequence (kSphereFrames frames, played over and over).
    constexpr std::size_t kSphereFrames = 12;
    std::unique_ptr<Sequence> sequence;
    std::vector<Object> objects;
    constexpr std::size_t kClothFrames = 6;  // (as `peelcd bench cloth-crumpled`'s default)
    std::vector<Mesh> cloth_frames;
    if (cloth) {
      for (std::size_t f = 0; f < kClothFrames; ++f) cloth_frames.push_back(make_crumpled_cloth(int(cloth), 0.15 * double(f)));
      objects.resize(1);
      objects[0].name = "cloth";
      objects[0].mesh = cloth_frames[0];
    } else if (stacks || wave || crowd) {
      sequence = stacks ? make_crossing_spheres(int(stacks), kSphereFrames, /*wave=*/false)
                 : wave ? make_crossing_spheres(int(wave), kSphereFrames, /*wave=*/true)
                        : make_crowd(std::size_t(crowd), kSphereFrames);
      sequence->frame(0, objects);
    } else {
      objects = load_objects(load_scene(path));
      for (Object& o : objects) o.rigid = RigidMotion{std::make_shared<const Mesh>(o.mesh), Eigen::Affine3d::Identity()};
    }
    std::shared_ptr<ImageStage> stage;
    if (image) {
#if PEELCD_HAVE_EGL
      gl::GlOptions gl;
      gl.resolve = Resolve::gpu;
      gl.coverage = Coverage::compute;
      gl.workers = unsigned(threads);
      stage = make_image_stage("egl", gl);
#else
      return usage("--image: this program was built without EGL");
#endif
    }
    World world(stage);
    if (model) {
      if (threads != 1) return usage("--model runs on one thread: leave --threads out");
      world.model_lanes(unsigned(model));
    }
    std::vector<BodyId> ids;
    for (const Object& o : objects)
      ids.push_back(o.rigid ? world.add_rigid(o.rigid->shape, o.rigid->pose, o.name) : world.add_deforming(o.mesh, o.name));
    if (cloth) world.set_self(ids[0], true);
    DetectOptions opt;
    opt.threads = unsigned(threads);
    if (pairs) opt.contacts = ContactDetail::pairs;
    if (image) opt.stage = Stage::image;
    FrameResult result;
    std::vector<char> other(cold ? std::size_t(64) << 20 : 0);
    std::vector<std::uint32_t> work(busy ? 200000 : 0);
    std::vector<double> ms, boxes, exact, one_lane, inside, upload, calls, readback, waits, modelled, modelled_frame, host,
        host_one_lane, modelled_host;
    struct LoopTimes {  // a loop of the lane model over the frames
      std::string step;
      std::vector<double> items, total, longest, span;
    };
    std::vector<LoopTimes> loops;
    std::size_t contacts = 0;
    for (long f = -warmup; f < frames; ++f) {
      for (std::size_t i = 0; i < other.size(); i += 64) other[i] = char(other[i] + 1);
      if (busy) {  // other work: a sort of random integers (xorshift, seeded by the frame)
        std::uint32_t x = std::uint32_t(f) * 2654435761u + 1;
        for (std::uint32_t& v : work) {
          x ^= x << 13;
          x ^= x >> 17;
          x ^= x << 5;
          v = x;
        }
        std::sort(work.begin(), work.end());
      }
      if (sequence) sequence->frame(std::size_t(f + warmup) % kSphereFrames, objects);
      if (cloth) objects[0].mesh.vertices = cloth_frames[std::size_t(f + warmup) % kClothFrames].vertices;
      const auto t0 = std::chrono::steady_clock::now();
      for (std::size_t i = 0; i < ids.size(); ++i) {
        if (objects[i].rigid) world.set_pose(ids[i], objects[i].rigid->pose);
        else world.set_vertices(ids[i], objects[i].mesh.vertices);
      }
      world.collide(opt, result);
      if (f < 0) continue;  // a warm-up frame
      ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      boxes.push_back(result.timings.aabb);
      exact.push_back(result.timings.cpu);
      one_lane.push_back(world.stats().one_lane_ms / result.timings.total);
      inside.push_back(result.timings.total);
      upload.push_back(result.timings.upload);
      calls.push_back(result.timings.gpu);
      readback.push_back(result.timings.readback);
      waits.push_back(result.timings.gl_wait);
      host.push_back(result.timings.total - result.timings.gpu - result.timings.readback);
      host_one_lane.push_back(world.stats().one_lane_ms - result.timings.gpu - result.timings.readback);
      for (const PairResult& p : result.pairs) contacts += p.colliding.size();
      if (model) {
        modelled.push_back(world.stats().model_ms / result.timings.total);
        double wall = 0.0, span = 0.0;  // the whole frame's loops: set_vertices()'s and collide()'s
        for (const LaneLoop& l : world.lane_loops()) wall += l.wall_ms, span += l.span_ms;
        modelled_frame.push_back((ms.back() - wall + span) / ms.back());
        double collide_spans = 0.0;  // (this collide()'s loops: those after set_vertices()'s)
        for (const LaneLoop& l : world.lane_loops())
          if (std::string(l.step) != "parts") collide_spans += l.span_ms;
        modelled_host.push_back(host_one_lane.back() + collide_spans);
        // (loops by their step and order within it: a frame's steps may run some loops twice)
        std::vector<int> seen;
        for (const LaneLoop& l : world.lane_loops()) {
          std::size_t k = 0;
          int nth = 0;
          for (const LaneLoop& m : world.lane_loops()) {
            if (&m == &l) break;
            nth += std::string(m.step) == l.step;
          }
          const std::string key = std::string(l.step) + (nth ? " #" + std::to_string(nth + 1) : "");
          while (k < loops.size() && loops[k].step != key) ++k;
          if (k == loops.size()) loops.push_back({key, {}, {}, {}, {}});
          loops[k].items.push_back(double(l.items));
          loops[k].total.push_back(l.total_ms);
          loops[k].longest.push_back(l.longest_ms);
          loops[k].span.push_back(l.span_ms);
        }
      }
    }
    const std::string what = stacks ? "spheres, " + std::to_string(stacks) + " stacks"
                             : wave  ? "waving spheres, " + std::to_string(wave) + " stacks"
                             : crowd ? "crowd, " + std::to_string(crowd) + " balls"
                             : cloth ? "crumpled cloth, " + std::to_string(2 * cloth * cloth) + " triangles, self" : path;
    std::printf("%s: %ld frames%s%s%s%s, %s\n", what.c_str(), frames,
                warmup ? (" after " + std::to_string(warmup) + " untimed").c_str() : "", pairs ? ", pairs only" : "",
                image ? ", the image route (EGL, GPU resolve, compute coverage)" : "",
                busy  ? ", 64 MB written and 200k integers sorted between frames"
                : cold ? ", 64 MB written between frames"
                       : "",
                threads == 1 ? "one thread" : threads == 0 ? "a thread per core" : (std::to_string(threads) + " threads").c_str());
    std::printf("frame: median %.4f ms, first quartile %.4f ms; boxes %.4f ms, exact %.4f ms (medians)\n", median(ms),
                median(ms, 0.25), median(boxes), median(exact));
    if (image)
      std::printf("image route: views %.4f ms, stage calls %.4f ms (GL waits %.4f), readback %.4f ms; collide() outside "
                  "the stage's calls and readback %.4f ms, of it outside the lanes' loops %.4f ms (medians)\n",
                  median(upload), median(calls), median(waits), median(readback), median(host), median(host_one_lane));
    // The share of collide() outside the loops the lanes share (WorldStats::one_lane_ms): with
    // one thread, what bounds the frame of more (Amdahl).
    // On the image route the stage's calls (a software renderer's seconds) are left out: the
    // share is of collide()'s host work.
    const double serial = image ? median(host_one_lane) / std::max(1e-12, median(host)) : median(one_lane);
    std::printf("collide(): median %.4f ms; %.1f%% of %s outside the lanes' loops (median)%s\n", median(inside),
                100.0 * serial, image ? "its host work (outside the stage's calls and readback) is" : "it is",
                threads == 1 ? (", so 8 threads take at least " + std::to_string(serial + (1.0 - serial) / 8.0).substr(0, 5) +
                                "x one" + (image ? " for that work" : "")).c_str()
                             : "");
    if (model && image)
      std::printf("lane model, %ld lanes: collide() outside the stage's calls and readback at best %.4f ms (median; the "
                  "steps between the loops and the loops' spans)\n", model, median(modelled_host));
    if (model) {
      std::printf("lane model, %ld lanes: by the work's balance, a frame (poses and vertices set, collide()) at best %.3fx "
                  "its one-thread time, collide() %.3fx (medians; the loops' spans and the steps between them)\n",
                  model, median(modelled_frame), median(modelled));
      std::printf("%-16s %8s %10s %10s %10s %8s %8s\n", "loop", "items", "work ms", "longest", "span ms", "work/L", "frames");
      for (const LoopTimes& l : loops)
        std::printf("%-16s %8.0f %10.4f %10.4f %10.4f %8.4f %8zu\n", l.step.c_str(), median(l.items), median(l.total),
                    median(l.longest), median(l.span), median(l.total) / double(model), l.items.size());
    }
    std::printf("contacts: %zu over the frames (%.1f a frame); last frame: %zu candidates, %zu node pairs\n", contacts,
                double(contacts) / double(frames), world.stats().candidates, world.stats().node_pairs);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "peelcd_world_loop: %s\n", e.what());
    return 1;
  }
}
