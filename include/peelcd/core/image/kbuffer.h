#pragma once
// The k-buffer resolve of single-pass peeling on the host: the same layers and PCS as
// shaders/abuffer_resolve.comp, bit for bit, computed from the buffers shaders/abuffer.frag
// fills. Where GL itself runs on the CPU (llvmpipe), the k-buffer is host memory mapped without a
// copy, and a compiled loop that sorts each texel's few fragments once beats the JIT-compiled
// compute shader, which rescans them once per layer (docs/performance.md).
#include "peelcd/core/image/id_map.h"

#include "peelcd/core/worker_pool.h"

#include <cmath>
#include <cstdint>
#include <vector>

namespace peelcd {

// One stored fragment (shaders/abuffer.frag): depth bits, object << 31 | draw order,
// dz/dx bits, dz/dy bits. Conservative (shaders/conservative.frag): lower depth bits,
// object << 31 | draw order, upper depth bits, 0.
struct KFragment {
  std::uint32_t depth, key, dzdx, dzdy;
};
static_assert(sizeof(KFragment) == 16, "a k-buffer fragment is one uvec4");

struct KBuffer {
  const std::uint32_t* counts = nullptr;  // per texel: fragments drawn (some maybe not stored)
  const KFragment* fragments = nullptr;   // slot s of texel t at s * texels + t
  int resolution = 0;                     // texels = resolution^2
  std::uint32_t slots = 0;                // fragments a texel can hold
  // Texels between a texel's consecutive slots: 0 = resolution^2 (one view's k-buffer); a view
  // packed with others (GlImageStage::peel_batch) passes the packed k-buffer's texel count, with
  // `counts` and `fragments` pointing at the view's first texel.
  std::size_t stride = 0;
  // Compact layout (the batched views' k-buffer, sized by a count pass): texel t's fragments at
  // fragments[offsets[t] .. offsets[t] + counts[t]) (`slots` then the deepest count, `stride`
  // unused). nullptr: the slot layout above.
  const std::uint32_t* offsets = nullptr;
};

struct KResolveParams {
  float epsilon_window = 0.0f;  // as shaders/abuffer_resolve.comp's uniforms
  float slope = 0.0f;
  bool full_peel = false;
  std::uint32_t first_object = 0;  // alternate: the object of layer 0
  // Fragments hold depth intervals (PeelJob::conservative): every fragment is a layer, and
  // every two fragments of different objects whose intervals overlap are a PCS.
  bool conservative = false;
  // Triangle ID by draw order, per object (the provoking corner's ID).
  const std::uint32_t* ids[2] = {nullptr, nullptr};
};

struct KResolveResult {
  std::uint32_t max_layers = 0;     // the most layers of any texel
  std::uint32_t max_fragments = 0;  // the most fragments of a texel that had more than `slots`
};

// Appends the PCS (ID of A, ID of B; unsorted, with repeats, though not of the last pair) to `pcs`. `scratch` holds one
// texel's fragments (reused: no allocation in steady state). With `layers`, also writes layer k
// of every texel into layers[k] (4 words per texel as the layer textures hold them, zero where
// a texel has no layer k; grown as needed).
KResolveResult resolve_kbuffer(const KBuffer& kb, const KResolveParams& p, std::vector<IdPair>& pcs,
                               std::vector<KFragment>& scratch,
                               std::vector<std::vector<std::uint32_t>>* layers = nullptr);

// resolve_kbuffer() split over a WorkerPool's lanes by blocks of texels (the PCS come in a
// different order, the same set). A resolve allocates nothing once the PCS lists have grown.
// With `layers` (a capture) it runs on the calling thread only.
class KResolver {
 public:
  explicit KResolver(WorkerPool& pool) : pool_(pool), lanes_(pool.lanes()) {}

  // Appends to `pcs` as resolve_kbuffer() does.
  KResolveResult resolve(const KBuffer& kb, const KResolveParams& p, std::vector<IdPair>& pcs,
                         std::vector<std::vector<std::uint32_t>>* layers = nullptr);

 private:
  struct Lane {
    std::vector<IdPair> pcs;
    std::vector<KFragment> scratch;
    KResolveResult result;
  };
  WorkerPool& pool_;
  std::vector<Lane> lanes_;
};

// The two PCS tests (pcs_within_epsilon, pcs_intervals_overlap), one source for this code and
// the GL stage's resolve shaders: peelcd/core/image/pcs_test.inc.
#define PEELCD_PCS_FN inline
#define PEELCD_ABS std::fabs
#include "peelcd/core/image/pcs_test.inc"
#undef PEELCD_PCS_FN
#undef PEELCD_ABS

}  // namespace peelcd
