#pragma once
// Request and result of one frame of detection (peelcd/core/image/detector.h runs it).
#include "peelcd/core/aabb.h"
#include "peelcd/core/pair_outcomes.h"
#include "peelcd/core/pairs.h"

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace peelcd {

// How layers are peeled. alternate: the paper's alternate surface peeling (docs/design.md 1.5);
// full: every surface of both objects, every adjacent A-B couple tested (a superset).
enum class PeelMode { alternate, full };
const char* to_string(PeelMode mode);
std::optional<PeelMode> parse_peel_mode(const std::string& text);

// Which triangles of a ROI are peeled. box: every triangle touching the ROI (the paper's way).
// contact: contact-region culling (core/image/cull.h): only the triangles whose boxes share a grid cell
// of the ROI with the other object's, the ROI shrunk to their boxes' overlap; conservative (no
// colliding pair is dropped), fewer triangles drawn and a finer tile on the same budget.
enum class Cull { box, contact };
const char* to_string(Cull cull);
std::optional<Cull> parse_cull(const std::string& text);

// Which stage tests a ROI (pair of objects whose boxes overlap). image: the image stage (peeled
// layers -> PCS -> exact test of their candidates). exact: the exact CPU path (the same culling,
// then every couple of kept triangles whose boxes overlap, found by a sweep along x, then the
// exact test): no GL work. automatic: per ROI, whichever a cost model calibrated for the image
// stage's backend (ImageStage::cost()) predicts cheaper (docs/performance.md, "The stage
// router"). The exact path is exact: routing to it never loses a contact.
enum class Stage { image, exact, automatic };
const char* to_string(Stage stage);
std::optional<Stage> parse_stage(const std::string& text);

// Triangle IDs written into the peel layers (peelcd/core/image/id_map.h): unique (a triangle's
// own index), paper (its last vertex, standing for every triangle whose last vertex it is) or
// ring (its last vertex, standing for the vertex's whole one-ring).
enum class IdMode { unique, paper, ring };

const char* to_string(IdMode mode);
std::optional<IdMode> parse_id_mode(const std::string& text);

// Which triangles of one object are adjacent, never a self pair (peelcd/core/exact/self.h):
// those sharing a vertex index, or a vertex position.
enum class SelfAdjacency { index, position };
const char* to_string(SelfAdjacency adjacency);
std::optional<SelfAdjacency> parse_self_adjacency(const std::string& text);

// What each contact holds (DetectOptions::contacts): its exact intersection segment and kind
// (segments), or the colliding pair alone (pairs: the same exact yes/no, as float peers return
// their pairs; kind unclassified, no segment). With pairs, each run of tests still classifies
// its contacts until it meets one that crosses, so that the object pair's relation (crossing,
// touching, containment) stays exact: those contacts keep their segment and kind.
enum class ContactDetail { segments, pairs };
const char* to_string(ContactDetail detail);
std::optional<ContactDetail> parse_contact_detail(const std::string& text);

// Defaults chosen on the per-class accuracy measurements of docs/accuracy.md and the benchmarks
// of docs/performance.md. The paper's own configuration (paper_options()) is conservative =
// false, theta = phi = roll = 0, ids = paper, peel = alternate, slope = 0, views = 1, cull = box.
struct DetectOptions {
  // The view frame: d(theta, phi) (degrees of longitude and latitude), its u and v axes turned
  // by `roll` degrees about d (view_frame()). The default is a fixed generic frame
  // (docs/accuracy.md, "The view frame"): in each of the three fused views, every plane
  // perpendicular to a world axis is at least 18 degrees from edge-on, and every plane through
  // a world axis at 45 degrees to the other two at least 8 degrees. theta = phi = roll = 0 is
  // the paper's frame, whose three views look along world x, y and z.
  double theta = 31.0;
  double phi = 51.0;
  double roll = 30.0;
  int resolution = 0;  // forced N x N tile per ROI; 0 = share the budget (allocate_tiles())
  int budget = 512;    // the frame's texture budget is budget x budget texels
  // Conservative image stage (docs/accuracy.md, "Conservative mode"): every triangle covers
  // every texel its projection touches, each fragment holds the depth interval its triangle
  // spans over the texel, and every two fragments of different objects whose intervals overlap
  // form a PCS. No colliding pair can be missed at any resolution; epsilon, slope, ids' loss and
  // the peel mode do not apply (every fragment is a layer). One view suffices.
  bool conservative = true;
  // unique: each fragment names its own triangle. With conservative coverage no neighbour has to
  // be recovered, so the PCS are the candidates (508 against ring IDs' 6,051 on the default
  // scene, no miss either way). Point sampling misses less with ring IDs (--ids ring).
  IdMode ids = IdMode::unique;
  double epsilon = 0.0;  // PCS depth threshold, world units; 0 = one texel of the ROI tile
                        // (of the culled region's tile with Cull::contact)
  PeelMode peel = PeelMode::full;  // full: no slower than alternate since the host resolve,
                                   // and more accurate (docs/performance.md)
  // Slope-following epsilon: a texel pair is a PCS when |dz| < epsilon + slope * (|dzdx_k+1 -
  // dzdx_k| + |dzdy_k+1 - dzdy_k|), i.e. when the two surfaces' planes meet within `slope`
  // texels of the texel centre. 0 = the paper's constant epsilon.
  double slope = 1.0;
  // Views fused per ROI: 1 = d(theta, phi) only; 2 = d and the frame's u axis; 3 = d, u and v
  // (three orthogonal views); the PCS of all views are united before the narrow phase. Two
  // views see every intersection segment at >= 1/sqrt(2) of its length, three at >= sqrt(2/3).
  int views = 1;
  Cull cull = Cull::contact;         // chosen on peelcd bench and sweep (docs/performance.md)
  // Sharing the budget (resolution == 0) with Cull::contact, a ROI's tile is at most the side
  // that gives the median edge of its kept triangles `edge_texels` texels
  // (edge_tile_resolution()): a contact between large triangles needs fewer texels than its
  // share of the budget. 0 = always the share. Unset: the mode's default (edge_texels_of()):
  // kConservativeEdgeTexels for the conservative stage, which is exact at any tile (a coarser
  // tile draws fewer fragments and tests more candidates), kPointEdgeTexels for point sampling,
  // whose misses grow with the texel. Chosen on docs/performance.md's measurements.
  std::optional<double> edge_texels;
  // Per ROI: image stage, exact CPU path, or the cheaper of the two by the cost model. Dumps,
  // goldens and sweeps set Stage::image (they check the image stage).
  Stage stage = Stage::automatic;
  // Threads for the per-object-pair CPU work: contact culling and the exact CPU path (pairs
  // spread over them; each pair's result is the same on any count). 1 = the calling thread
  // only; 0 = the hardware's threads, at most 8. The GL stage's host resolve has its own lanes
  // (gl::GlOptions::workers).
  unsigned threads = 1;
  // Self-collision (docs/design.md, "Self-collision") of every object; an object asks it for
  // itself alone with Object::self. Off by default: it costs a scan of the object's triangles.
  bool self = false;
  SelfAdjacency self_adjacency = SelfAdjacency::index;  // which triangles of one object are adjacent
  // The intersection volume of each pair of closed objects whose boxes overlap
  // (PairResult::volume; peelcd/core/exact/relation.h), with resolution x resolution rays per axis
  // (kVolumeResolution when resolution is 0). Off by default.
  bool volume = false;
  // A penetration direction and depth for each colliding or containing pair of closed objects
  // (PairResult::depth; peelcd/core/exact/depth.h). Off by default.
  bool depth = false;
  // Proximity: with a margin m > 0, object pairs whose boxes are within m of each other are pairs
  // of the frame, and each gets its triangle pairs within m with their distances and its least
  // distance (PairResult::near; peelcd/core/exact/proximity.h). 0 (the default): off.
  double margin = 0.0;
  // At most this many contacts per object pair (0: every one). The exact tests of a pair stop at
  // the N-th colliding triangle pair found (a first-contact query: 1), in candidate order; the
  // pair still collides (is_collision()), its relation is decided from the contacts found
  // (relation_note says so) and the candidates are found whole.
  std::size_t max_contacts = 0;
  // Each contact with its segment and kind (the default), or the colliding pairs alone
  // (ContactDetail::pairs: cheaper where most pairs collide; docs/api.md).
  ContactDetail contacts = ContactDetail::segments;
};

constexpr int kVolumeResolution = 256;

// The texels per median edge of a ROI's kept triangles when its tile shares the budget
// (DetectOptions::edge_texels unset): the conservative stage's and point sampling's defaults.
constexpr double kConservativeEdgeTexels = 2.0;
constexpr double kPointEdgeTexels = 12.0;
// The texels per median edge `options` asks for: its edge_texels, or the mode's default.
double edge_texels_of(const DetectOptions& options);


// The paper's configuration (ISVC 2007): alternate peeling of every triangle in the ROI box,
// constant epsilon of one texel, the paper's IDs, one view along world x, point sampling.
DetectOptions paper_options();

struct PairResult {
  std::size_t object_a = 0, object_b = 0;  // indices into the frame's objects, a < b; a == b: the
                                           // object's self pairs (tri_a < tri_b)
  Aabb roi;                                // intersection of the two world AABBs
  Aabb region;                             // the box peeled: `roi`, or with Cull::contact the
                                           // ROI shrunk to the kept triangles (empty: none kept)
  // Triangles touching `roi`, before culling (Cull::box: those touching the padded ROI of the
  // first view, i.e. the triangles drawn).
  std::size_t triangles_in_roi_a = 0, triangles_in_roi_b = 0;
  int resolution = 0;
  double epsilon = 0.0;                    // world units
  bool a_first = false;                    // A was peeled first (it was the farther one)
  std::size_t triangles_drawn_a = 0, triangles_drawn_b = 0;
  int layers = 0;                          // non-empty logical layers peeled (most of any view)
  int passes = 0;                          // peel passes drawn (layers + the final empty one), all views
  std::size_t pcs_count = 0;               // distinct ID pairs read back
  std::vector<IdPair> pcs;                 // those pairs (ID of A, ID of B), sorted
  std::size_t candidates = 0;              // distinct triangle pairs tested on the CPU
  bool exact_stage = false;                // tested by the exact CPU path (no image work)
  bool margin_fallback = false;            // ... because the margin is too wide for the image stage
                                           // (kImageMarginShare, peelcd/core/image/planner.h)
  int views_peeled = 0;                    // ROI views given to the image stage
  int views_exhaustive = 0;                // of those, views the stage could not hold (a k-buffer
                                           // deeper or larger than the context allows): their
                                           // box-overlapping triangle couples were tested exactly
  // The stage router's predictions for this ROI, milliseconds (0 when it did not route).
  double predicted_image_ms = 0.0, predicted_exact_ms = 0.0;
  std::vector<Contact> colliding;          // sorted by (tri_a, tri_b)
  // How the two objects relate (peelcd/core/exact/relation.h): from the contacts, or, with none,
  // containment (a closed object wholly inside the other: a collision with no contact).
  // Self pairs: crossing, touching or disjoint. `relation_note`: why unknown, or a detail.
  Relation relation = Relation::disjoint;
  std::string relation_note;
  VolumeEstimate volume;  // DetectOptions::volume: the intersection volume (volume.known)
  // DetectOptions::depth: move A by depth.depth * depth.direction to separate it from B
  // (depth.known; a pair that does not collide has none, and says so in depth.reason).
  PenetrationDepth depth;
  // DetectOptions::margin > 0: the triangle pairs within the margin (distance 0 where they meet)
  // and the least distance with its witness points (near.within(): some pair is within it).
  Proximity near;
  // A collision: a contact, or one object inside the other.
  bool is_collision() const { return !colliding.empty() || colliding_relation(relation); }
};

struct Timings {  // milliseconds, as in the paper's tables
  // aabb: bounds, the broad phase, the World's tree traversals, culling and routing; upload: the
  // image stage's views and their triangles gathered (the World's image route: regions, tiles,
  // jobs, moving meshes' vertices; the copying route's candidates' triangles), uploads; gpu: the image stage's calls that draw and dispatch, timed on the
  // host (its GL waits included); readback: reading layers and PCS back; cpu: the exact tests,
  // relations and the rest of the narrow phase; total: the frame.
  double aabb = 0, upload = 0, gpu = 0, readback = 0, cpu = 0, total = 0;
  // Host time blocked in GL calls that wait for the GPU (reads back, maps, query results): the
  // frame's host work is total - gl_wait. 0 on the CPU stage and the exact path.
  double gl_wait = 0;
  // GPU time of the image stage's passes, measured by GL timer queries (GL_TIME_ELAPSED) when the
  // stage times its passes (ImageStage::set_pass_timing; peelcd detect --timings, peelcd bench):
  // raster (draws: peel passes, k-buffer draws, the batch's count and fill passes), compute
  // (dispatches: selection, prefix sums, resolves, PCS tests) and transfer (buffer uploads,
  // clears and copies on the GPU's timeline). All 0 when not timed.
  double gpu_raster = 0, gpu_compute = 0, gpu_transfer = 0;
  // Parts of gpu_compute: the batch's triangle selection (its three dispatches) and the
  // conservative coverage by compute (GlOptions::coverage); the rest of gpu_compute is the
  // prefix sums, resolves and PCS tests.
  double gpu_select = 0, gpu_cover = 0;
  bool gpu_timed = false;  // the GPU times above were measured this frame
  // Passes whose query gave an impossible time (longer than the stage call that issued it: Mesa's
  // llvmpipe reports such for a pass its threads had no work in), left out of the three above.
  std::size_t gpu_passes_untimed = 0;
};

struct FrameResult {
  std::vector<PairResult> pairs;  // one per overlapping AABB pair, sorted by (a, b)
  Timings timings;
  std::size_t gl_passes = 0;      // draw + compute passes issued this frame (0 without a ROI)
  // What the frame skipped and did (the per-frame counters of peelcd simulate):
  std::size_t rois_peeled = 0;          // ROI views peeled (a ROI where one object has no
                                        // triangle inside does no GL work)
  std::size_t triangles_uploaded = 0;   // triangles whose corners were uploaded (only those
                                        // touching a ROI)
  std::size_t triangles_indexed = 0;    // rigid objects' triangles drawn from their cached
                                        // shape: only indices uploaded
  std::size_t shape_uploads = 0;        // rigid shapes uploaded (once each; 0 in steady state)
  std::size_t pcs_readbacks = 0;        // PCS lists read back (none when a ROI's count is 0)
  std::size_t views_exhaustive = 0;     // conservative views no k-buffer could hold: their
                                        // triangles' box-overlapping couples went to the exact test
  std::size_t rois_exact = 0;           // ROIs the exact CPU path tested (Stage::exact, or routed)
  // The image stage's GL calls this frame (draws, dispatches, readbacks, bytes up and down; all 0
  // on the CPU stage and on the exact path).
  std::size_t gl_draws = 0, gl_dispatches = 0, gl_readbacks = 0, bytes_uploaded = 0, bytes_read = 0;
  // Of bytes_uploaded, mesh data (corners, indices, draw entries: StageCounters::geometry_bytes).
  std::size_t geometry_bytes = 0;
  // The GPU resolve's texels deeper than one invocation resolves (PEELCD_GPU_RESOLVE_DEPTH
  // fragments): split over invocations (batched conservative views: gl_deep_texels), or their
  // views resolved on the host instead (views_host_resolved). Both 0 on the host resolve.
  std::size_t gl_deep_texels = 0, views_host_resolved = 0;
  // Texel couples the GPU resolve's certified filter dropped (their triangles proved farther
  // apart than the margin; a triangle pair counts once per texel where it overlaps in depth);
  // 0 where the filter does not run (the host resolve, views drawn alone, --no-gpu-filter).
  std::size_t gl_couples_apart = 0;
  std::string renderer;           // GL_RENDERER of the context that ran it

  // Every counter and timing to zero (the pairs and the renderer stay): a frame's start.
  void reset_counters();
  // Adds `other`'s image-stage work to this frame's: GL passes, views peeled, uploads, readbacks,
  // exhaustive views, the GL calls and bytes, deep texels, and the aabb, upload, gpu, readback, cpu,
  // GL wait and GPU pass timings (the World's image-routed pairs, run as a frame of their own).
  void add_image_work(const FrameResult& other);
};

}  // namespace peelcd
