#include "peelcd/bench/self_bench.h"
#include "peelcd/core/clock.h"

#include "exact/bvh_traverse.h"  // the library's own self traversal (core/ on the bench's path)
#include "peelcd/bench/float_peers.h"
#include "peelcd/bench/plain_peers.h"
#include "peelcd/bench/suite.h"
#include "peelcd/core/exact/bvh.h"
#include "peelcd/core/image/detector.h"
#include "peelcd/core/image/id_map.h"
#include "peelcd/core/exact/self.h"
#include "peelcd/core/world/world.h"
#include "peelcd/core/primitives.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <chrono>
#include <cstdio>
#include <functional>
#include <map>

namespace peelcd::bench {
namespace {

// Frame f of the fold: the top layer sinks through the bottom as f grows; of the crumpled
// cloth: its folds drift.
Mesh cloth_frame(const SelfSuite& suite, std::size_t f, std::size_t frames) {
  if (suite.crumpled) return make_crumpled_cloth(suite.n, 0.15 * double(f));
  const double t = 0.6 + 0.4 * double(f) / double(std::max<std::size_t>(1, frames - 1));
  return make_folded_sheet(suite.n, 0.3 * (1.2 - t), 0.4 * t);
}

std::vector<std::uint64_t> keys_of(const std::vector<Contact>& contacts) {
  std::vector<std::uint64_t> k;
  for (const Contact& c : contacts) k.push_back(pack_pair(c.tri_a, c.tri_b));
  std::sort(k.begin(), k.end());
  return k;
}

}  // namespace

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SM = CGAL::Surface_mesh<K::Point_3>;

// A method: fn(frame) -> its pairs (packed, tri_a < tri_b, sorted).
struct Method {
  std::string name;
  std::function<std::vector<std::uint64_t>(std::size_t)> run;
};

// What the methods keep between frames, made before the timed frames (trees, the World's body),
// as a simulation would keep it.
struct SelfState {
  explicit SelfState(const SelfSuite& suite) : world(suite.stage), pairs_world(suite.stage), detector(suite.stage) {}
  std::vector<Mesh> meshes;
  World world, pairs_world;  // the default, and the default asking for pairs only
  BodyId cloth = 0, pairs_cloth = 0;
  Detector detector;
  std::vector<Object> objects{1}, peer_objects{1};
  FrameResult frame;
  EmbreePeer embree{EmbreePeer::Update::refit, 1};
  EmbreePeer embree_morton{EmbreePeer::Update::rebuild_low, 1};
  BulletPeer bullet{1};
  PlainPeer plain_embree{PlainPeer::Library::embree};  // --audit
  Bvh tree;
  std::vector<std::uint32_t> rep;
  std::vector<BvhNodePair> stack;
  std::vector<SM> sms;
};

// peelcd's rows: the World (and again asking for pairs only), the frame API's three stages.
void add_peelcd_methods(SelfState& st, std::vector<Method>& methods) {
  st.cloth = st.world.add_deforming(st.meshes[0], "cloth");
  st.world.set_self(st.cloth, true);
  methods.push_back({"peelcd World (default)", [&st](std::size_t f) {
                       st.world.set_vertices(st.cloth, st.meshes[f].vertices);
                       const FrameResult& r = st.world.collide(DetectOptions{});
                       return r.pairs.empty() ? std::vector<std::uint64_t>{} : keys_of(r.pairs[0].colliding);
                     }});
  st.pairs_cloth = st.pairs_world.add_deforming(st.meshes[0], "cloth");
  st.pairs_world.set_self(st.pairs_cloth, true);
  methods.push_back({"peelcd World, pairs only", [&st](std::size_t f) {
                       st.pairs_world.set_vertices(st.pairs_cloth, st.meshes[f].vertices);
                       DetectOptions opt;
                       opt.contacts = ContactDetail::pairs;  // no segment or kind, as the peers report
                       const FrameResult& r = st.pairs_world.collide(opt);
                       return r.pairs.empty() ? std::vector<std::uint64_t>{} : keys_of(r.pairs[0].colliding);
                     }});
  st.objects[0].name = "cloth";
  st.objects[0].self = true;
  const auto frame_api = [&st](Stage stage) {
    return [&st, stage](std::size_t f) {
      Object& o = st.objects[0];
      o.mesh.vertices = st.meshes[f].vertices;
      if (o.mesh.triangles.size() != st.meshes[f].triangles.size()) o.mesh.triangles = st.meshes[f].triangles;
      DetectOptions opt;
      opt.stage = stage;
      st.detector.detect(st.objects, opt, st.frame);
      return st.frame.pairs.empty() ? std::vector<std::uint64_t>{} : keys_of(st.frame.pairs[0].colliding);
    };
  };
  methods.push_back({"peelcd frame API, stage auto", frame_api(Stage::automatic)});
  methods.push_back({"peelcd frame API, exact path", frame_api(Stage::exact)});
  methods.push_back({"peelcd frame API, image stage", frame_api(Stage::image)});
}

// The peers: Embree and Bullet (the cloth as one deforming object against itself, their trees
// refitted; Embree's also rebuilt at low quality, its Morton builder: the faster of the two is
// the one an Embree user would pick), a bare BVH self-test with peelcd's tree and test, CGAL's self_intersections.
void add_peer_methods(SelfState& st, std::vector<Method>& methods, bool audit) {
  st.peer_objects[0].name = "cloth";
  st.peer_objects[0].self = true;
  const auto peer = [&st](auto& p) {
    return [&st, &p](std::size_t f) {
      Object& o = st.peer_objects[0];
      o.mesh.vertices = st.meshes[f].vertices;  // the frame's input, as the World's set_vertices
      // The topology is the first frame's throughout (as the World's body keeps it).
      if (o.mesh.triangles.size() != st.meshes[f].triangles.size()) o.mesh.triangles = st.meshes[f].triangles;
      PeerFrame r = p.frame(st.peer_objects);
      return r.per_pair.empty() ? std::vector<std::uint64_t>{} : std::move(r.per_pair[0]);
    };
  };
  methods.push_back({"Embree 3 rtcCollide, self, refit", peer(st.embree)});
  methods.push_back({"Embree 3 rtcCollide, self, Morton rebuild", peer(st.embree_morton)});
  methods.push_back({"Bullet 3 GImpact, self, refit", peer(st.bullet)});
  if (audit) methods.push_back({"Embree 3 rtcCollide, self, plain setup (audit)", peer(st.plain_embree)});
  // A BVH self-test with its tree kept: refit, traverse against itself, drop adjacent couples,
  // the exact test (peelcd's Bvh and test, no World around them).
  st.tree.build(st.meshes[0].vertices, st.meshes[0].triangles);
  vertex_representatives(st.meshes[0], SelfAdjacency::index, st.rep);
  methods.push_back({"BVH self-test (tree kept, refit)", [&st](std::size_t f) {
                       const Mesh& m = st.meshes[f];
                       st.tree.refit(m.vertices, m.triangles);
                       std::vector<std::uint64_t> out;
                       bvh_self_traverse(st.tree, st.stack, [&](std::uint32_t x, std::uint32_t y) {
                         if (triangles_adjacent(m, st.rep, x, y)) return;
                         if (triangles_intersect(corners(m, x), corners(m, y)))
                           out.push_back(x < y ? pack_pair(x, y) : pack_pair(y, x));
                       });
                       std::sort(out.begin(), out.end());
                       return out;
                     }});
  // CGAL: each frame's Surface_mesh made before timing (its points cannot be updated per frame
  // without a copy: the copy is made outside the timed call).
  st.sms.resize(st.meshes.size());
  for (std::size_t f = 0; f < st.meshes.size(); ++f) {
    std::vector<SM::Vertex_index> vs;
    for (const Vec3& v : st.meshes[f].vertices) vs.push_back(st.sms[f].add_vertex(K::Point_3(v.x(), v.y(), v.z())));
    for (const Tri& t : st.meshes[f].triangles) st.sms[f].add_face(vs[t[0]], vs[t[1]], vs[t[2]]);
  }
  methods.push_back({"CGAL PMP::self_intersections", [&st](std::size_t f) {
                       std::vector<std::pair<SM::Face_index, SM::Face_index>> out;
                       CGAL::Polygon_mesh_processing::self_intersections(faces(st.sms[f]), st.sms[f],
                                                                         std::back_inserter(out));
                       std::vector<std::uint64_t> k;
                       for (const auto& [x, y] : out) {
                         const std::uint32_t a = std::uint32_t(x.idx()), b = std::uint32_t(y.idx());
                         // CGAL also reports adjacent faces that meet beyond their shared vertex
                         // or edge; peelcd's definition excludes them (docs/design.md).
                         if (triangles_adjacent(st.meshes[f], st.rep, a, b)) continue;
                         k.push_back(a < b ? pack_pair(a, b) : pack_pair(b, a));
                       }
                       std::sort(k.begin(), k.end());
                       return k;
                     }});
}

// One method's timed frames and scores.
struct Tally {
  std::vector<double> ms;
  std::size_t exact = 0, found = 0, false_pairs = 0;
};

// Method m on frame f, timed, scored against the exact pairs; its line into `csv`.
void time_frame(Method& m, std::size_t f, const std::vector<std::uint64_t>& exact, Tally& t, std::string& csv) {
  const auto t0 = Clock::now();
  const std::vector<std::uint64_t> got = m.run(f);
  t.ms.push_back(ms_since(t0));
  std::vector<std::uint64_t> both;
  std::set_intersection(got.begin(), got.end(), exact.begin(), exact.end(), std::back_inserter(both));
  t.exact += exact.size();
  t.found += both.size();
  t.false_pairs += got.size() - both.size();
  char line[200];
  std::snprintf(line, sizeof line, "%s,%zu,%.4f,%zu,%zu,%zu,%zu\n", m.name.c_str(), f, t.ms.back(), exact.size(),
                both.size(), exact.size() - both.size(), got.size() - both.size());
  csv += line;
}

// --scaling N: the World's default (a kept body) and the frame API's exact path, each on one and
// on N threads, the two alone over the frames after an untimed pass, alternating frame by frame.
void print_scaling(const SelfSuite& suite, const std::vector<Mesh>& meshes,
                   const std::vector<std::vector<std::uint64_t>>& exact) {
  const unsigned threads[2] = {1u, suite.scaling};
  World worlds[2] = {World(suite.stage), World(suite.stage)};
  BodyId cloth[2];
  std::vector<std::unique_ptr<Detector>> detectors;
  std::vector<Object> objects[2];
  for (int k = 0; k < 2; ++k) {
    cloth[k] = worlds[k].add_deforming(meshes[0], "cloth");
    worlds[k].set_self(cloth[k], true);
    detectors.push_back(std::make_unique<Detector>(suite.stage));
    objects[k].resize(1);
    objects[k][0].name = "cloth";
    objects[k][0].self = true;
    objects[k][0].mesh = meshes[0];
  }
  FrameResult frame;
  // One frame of row r (0, 1: the World; 2, 3: the frame API; even: one thread): its pairs.
  const auto run = [&](int r, std::size_t f) {
    const int k = r % 2;
    DetectOptions opt;
    opt.threads = threads[k];
    if (r < 2) {
      worlds[k].set_vertices(cloth[k], meshes[f].vertices);
      const FrameResult& res = worlds[k].collide(opt);
      return res.pairs.empty() ? std::vector<std::uint64_t>{} : keys_of(res.pairs[0].colliding);
    }
    opt.stage = Stage::exact;
    objects[k][0].mesh.vertices = meshes[f].vertices;
    detectors[std::size_t(k)]->detect(objects[k], opt, frame);
    return frame.pairs.empty() ? std::vector<std::uint64_t>{} : keys_of(frame.pairs[0].colliding);
  };
  const char* names[2] = {"peelcd World (default)", "peelcd frame API, exact path"};
  for (int api = 0; api < 2; ++api) {
    std::vector<double> ms[2];
    std::size_t missed[2] = {0, 0};
    for (int pass = 0; pass < 2; ++pass)
      for (std::size_t f = 0; f < meshes.size(); ++f)
        for (int k = 0; k < 2; ++k) {
          const auto t0 = Clock::now();
          const std::vector<std::uint64_t> got = run(2 * api + k, f);
          if (pass == 0) continue;  // (untimed)
          ms[k].push_back(ms_since(t0));
          std::vector<std::uint64_t> both;
          std::set_intersection(got.begin(), got.end(), exact[f].begin(), exact[f].end(), std::back_inserter(both));
          missed[k] += exact[f].size() - both.size();
        }
    std::printf("scaling: %s, %u threads / 1 thread, the two alone, alternating frame by frame: %.2f (medians %.3f / "
                "%.3f ms; missed %zu / %zu)\n",
                names[api], suite.scaling, median(ms[1]) / median(ms[0]), median(ms[1]), median(ms[0]), missed[1],
                missed[0]);
  }
}

}  // namespace

std::string run_self_suite(const SelfSuite& suite) {
  const std::size_t frames = std::max<std::size_t>(1, suite.frames);
  SelfState st(suite);
  for (std::size_t f = 0; f < frames; ++f) st.meshes.push_back(cloth_frame(suite, f, frames));
  std::vector<std::vector<std::uint64_t>> exact;
  for (const Mesh& m : st.meshes) exact.push_back(exact_self_pairs(m));
  std::vector<Method> methods;
  add_peelcd_methods(st, methods);
  add_peer_methods(st, methods, suite.audit);

  std::printf("peelcd bench: %s (%s; %zu triangles, %zu frames, %zu exact self pairs in the first); "
              "median ms per frame after an untimed pass, the methods taking turns on each frame, one thread\n",
              suite.crumpled ? "cloth-crumpled" : "cloth-self",
              suite.crumpled ? "a cloth crumpled over a ball, its folds drifting" : "a folded cloth folding through itself",
              st.meshes[0].triangles.size(), frames, exact[0].size());
  std::printf("%-36s %10s %8s %10s %10s %8s %8s\n", "method", "median ms", "ratio", "exact", "found", "missed", "false");
  std::string csv = "method,frame,ms,exact,found,missed,false\n";
  // An untimed pass of every method over the frames (first-frame work), then the timed frames
  // with the methods taking turns on each (a change in the machine's load reaches every row).
  for (Method& m : methods)
    for (std::size_t f = 0; f < frames; ++f) m.run(f);
  std::vector<Tally> tally(methods.size());
  for (std::size_t f = 0; f < frames; ++f)
    for (std::size_t k = 0; k < methods.size(); ++k) time_frame(methods[k], f, exact[f], tally[k], csv);
  const double first = median(tally[0].ms);
  for (std::size_t k = 0; k < methods.size(); ++k) {
    const Tally& t = tally[k];
    const double med = median(t.ms);
    std::printf("%-36s %10.3f %8.3f %10zu %10zu %8zu %8zu\n", methods[k].name.c_str(), med, med / first, t.exact,
                t.found, t.exact - t.found, t.false_pairs);
  }
  std::printf("(ratio: to the first row. exact: the exact self pairs summed over the frames (docs/design.md's "
              "definition; CGAL's own adjacent-face reports are left out of its count).)\n");
  // --audit: the Embree self rows against Embree's scene against itself as a plain user sets it up.
  std::size_t plain = methods.size();
  for (std::size_t k = 0; k < methods.size(); ++k)
    if (methods[k].name.find("(audit)") != std::string::npos) plain = k;
  if (plain < methods.size())
    for (std::size_t k = 0; k < methods.size(); ++k)
      if (k != plain && methods[k].name.rfind("Embree", 0) == 0)
        std::printf("audit: %s / the plain setup: %.2f (medians %.3f / %.3f ms; pairs %zu / %zu over the frames)\n",
                    methods[k].name.c_str(), median(tally[k].ms) / median(tally[plain].ms), median(tally[k].ms),
                    median(tally[plain].ms), tally[k].found, tally[plain].found);
  if (suite.scaling) print_scaling(suite, st.meshes, exact);
  return csv;
}

}  // namespace peelcd::bench
