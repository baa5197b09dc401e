#pragma once
// The golden cases (docs/golden-images.md): fixtures/golden/<case>/case.json, a scene file, and
// <case>/expected/, its dump. Finding the cases, their scenes, and replacing a case's goldens.
#include "peelcd/oracle/dump.h"

#include <string>
#include <vector>

namespace peelcd::oracle {

// The cases in `dir` (folders with a case.json), sorted. Throws InputError when `dir` is not a
// folder or holds no case.
std::vector<std::string> golden_case_names(const std::string& dir);
// The scene file of case `name`. Throws InputError naming the case when it has none.
std::string golden_case_scene(const std::string& dir, const std::string& name);
// The folder of case `name`'s goldens.
std::string golden_case_expected(const std::string& dir, const std::string& name);
// Replaces case `name`'s goldens by `dump` whole (written beside, then renamed), signals held.
void record_golden_case(const Dump& dump, const std::string& dir, const std::string& name);
// The production path against a case's goldens: the frame a GPU runs by default (the views
// batched, rigid triangles selected on the GPU, the k-buffer resolved by compute), which
// captures no layer, so its pairs are compared, on every tier: in the conservative mode the
// colliding set must be the golden's; in a lossy configuration (point sampling, whose drawn
// triangles the GPU's selection may change) the misses against the exact reference may exceed
// the golden's by hardware_miss_slack(). Its PCS are noted (counts), never compared: the GPU's
// selection draws other triangles than the host's culling.
Comparison compare_production(const Dump& expected, const FrameResult& frame, bool conservative);

// Every K-th case from the (shard+1)-th: the slice `shard` of `shards`.
std::vector<std::string> golden_shard(const std::vector<std::string>& cases, std::size_t shard, std::size_t shards);

}  // namespace peelcd::oracle
