#include "peelcd/core/options.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>

namespace peelcd {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
using K = OptionSpec::Kind;

double num(const OptionValue& v) { return std::get<double>(v); }
const std::string& word(const OptionValue& v) { return std::get<std::string>(v); }

// "a,b,c" -> "a, b or c"
std::string choice_list(const char* choices) {
  std::vector<std::string> words;
  std::string w;
  for (const char* c = choices;; ++c) {
    if (*c == ',' || *c == 0) {
      words.push_back(w);
      w.clear();
      if (*c == 0) break;
    } else {
      w += *c;
    }
  }
  std::string out;
  for (std::size_t i = 0; i < words.size(); ++i)
    out += (i == 0 ? "" : i + 1 == words.size() ? " or " : ", ") + words[i];
  return out;
}

bool is_choice(const char* choices, const std::string& text) {
  std::string w;
  for (const char* c = choices;; ++c) {
    if (*c == ',' || *c == 0) {
      if (w == text) return true;
      w.clear();
      if (*c == 0) return false;
    } else {
      w += *c;
    }
  }
}

const std::vector<OptionSpec> kTable = {
    {"conservative", "", "--conservative",
     "Conservative image stage (the default): every texel a triangle touches, depth intervals, every overlapping "
     "couple a PCS; no colliding pair can be missed (docs/accuracy.md). --no-conservative: point sampling at texel "
     "centres with the epsilon test (the paper's image stage; may miss pairs)",
     K::boolean, 0, 0, "must be true or false", "", "", true,
     [](const DetectOptions& o) { return OptionValue(o.conservative); },
     [](DetectOptions& o, const OptionValue& v) { o.conservative = std::get<bool>(v); }},
    {"theta", "view", "--theta", "View longitude, degrees", K::number, -kInf, kInf, "must be finite", "", "", true,
     [](const DetectOptions& o) { return OptionValue(o.theta); },
     [](DetectOptions& o, const OptionValue& v) { o.theta = num(v); }},
    {"phi", "view", "--phi", "View latitude, degrees, in [-90, 90]", K::number, -90, 90,
     "must be within [-90, 90] degrees", "", "", true, [](const DetectOptions& o) { return OptionValue(o.phi); },
     [](DetectOptions& o, const OptionValue& v) { o.phi = num(v); }},
    {"roll", "view", "--roll",
     "Turn of the view frame's u and v axes about d, degrees (default 30 with the default theta 31, phi 51; 0 when "
     "--theta or --phi is given)",
     K::number, -kInf, kInf, "must be finite", "", "", true, [](const DetectOptions& o) { return OptionValue(o.roll); },
     [](DetectOptions& o, const OptionValue& v) { o.roll = num(v); }},
    {"resolution", "", "--res", "Forced N x N texture per ROI (default 0: tiles by need within the budget)",
     K::integer, 0, 32768, "must be within 0..32768 (0 = from the budget; a stage may allow less: its largest texture, 16384 on llvmpipe)", "", "", true,
     [](const DetectOptions& o) { return OptionValue(double(o.resolution)); },
     [](DetectOptions& o, const OptionValue& v) { o.resolution = int(num(v)); }},
    {"budget", "", "--budget", "The frame's texture budget: N x N texels shared by the ROIs (default 512)",
     K::integer, 1, 1 << 20, "must be positive", "", "", true,
     [](const DetectOptions& o) { return OptionValue(double(o.budget)); },
     [](DetectOptions& o, const OptionValue& v) { o.budget = int(num(v)); }},
    {"ids", "", "--ids",
     "Triangle ID mode: unique (each triangle its own; default), ring (last vertex, whole one-ring: better for "
     "point sampling) or paper (last-vertex IDs, T(v) sets)",
     K::choice, 0, 0, "", "paper,ring,unique", "ID mode", true,
     [](const DetectOptions& o) { return OptionValue(std::string(to_string(o.ids))); },
     [](DetectOptions& o, const OptionValue& v) { o.ids = *parse_id_mode(word(v)); }},
    {"epsilon", "", "--epsilon", "PCS depth threshold in world units (default 0: one texel)", K::number, 0, kInf,
     "must be >= 0 (0 = one texel)", "", "", true, [](const DetectOptions& o) { return OptionValue(o.epsilon); },
     [](DetectOptions& o, const OptionValue& v) { o.epsilon = num(v); }},
    {"peel", "", "--peel", "Peel mode: full (every surface; default) or alternate (the paper's)", K::choice, 0, 0, "",
     "full,alternate", "peel mode", true,
     [](const DetectOptions& o) { return OptionValue(std::string(to_string(o.peel))); },
     [](DetectOptions& o, const OptionValue& v) { o.peel = *parse_peel_mode(word(v)); }},
    {"slope", "", "--slope", "Slope-following epsilon, in texels (default 1; 0 = the paper's constant epsilon)",
     K::number, 0, kInf, "must be >= 0 (0 = constant epsilon)", "", "", true,
     [](const DetectOptions& o) { return OptionValue(o.slope); },
     [](DetectOptions& o, const OptionValue& v) { o.slope = num(v); }},
    {"views", "", "--views",
     "Views fused per ROI: 1 (along d; default), 2 (along d and u) or 3 (d, u and v, three orthogonal views)",
     K::integer, 1, 3, "must be 1, 2 or 3", "", "", true, [](const DetectOptions& o) { return OptionValue(double(o.views)); },
     [](DetectOptions& o, const OptionValue& v) { o.views = int(num(v)); }},
    {"cull", "", "--cull",
     "Triangles peeled per ROI: contact (only those sharing a grid cell of the ROI with the other object, the ROI "
     "shrunk to them; default) or box (all touching the ROI, the paper's)",
     K::choice, 0, 0, "", "contact,box", "culling", true,
     [](const DetectOptions& o) { return OptionValue(std::string(to_string(o.cull))); },
     [](DetectOptions& o, const OptionValue& v) { o.cull = *parse_cull(word(v)); }},
    {"edge_texels", "", "--edge-texels",
     "Sharing the budget with contact culling, a ROI's tile is at most K texels per median edge of its triangles "
     "across the culled region (default 2 with the conservative stage, 12 with point sampling; 0 = always the "
     "budget's share)",
     K::number, 0, kInf, "must be >= 0 (0 = the budget's share)", "", "", true,
     [](const DetectOptions& o) { return OptionValue(edge_texels_of(o)); },
     [](DetectOptions& o, const OptionValue& v) { o.edge_texels = num(v); }},
    {"stage", "", "--stage",
     "Per ROI: auto (the cheaper of the image stage and the exact CPU path by the backend's cost model; default of "
     "detect), image (always peel) or exact (no image stage: culling, box overlaps, exact test). dump always peels",
     K::choice, 0, 0, "", "auto,image,exact", "stage", true,
     [](const DetectOptions& o) { return OptionValue(std::string(to_string(o.stage))); },
     [](DetectOptions& o, const OptionValue& v) { o.stage = *parse_stage(word(v)); }},
    {"threads", "", "--threads",
     "Threads for contact culling and the exact CPU path, object pairs spread over them (default 1; 0 = one per "
     "core, at most 8); the results do not depend on it",
     K::integer, 0, 64, "must be within 0..64 (0 = one per core, at most 8)", "", "", false,
     [](const DetectOptions& o) { return OptionValue(double(o.threads)); },
     [](DetectOptions& o, const OptionValue& v) { o.threads = unsigned(num(v)); }},
    {"self", "", "--self",
     "Self-collision for every object (an object's own \"self\": true in a scene, Object::self in the API, asks it "
     "for that object alone): pairs of one object's triangles that share a point and no vertex (docs/design.md)",
     K::boolean, 0, 0, "must be true or false", "", "", kRecordedWhenSet,
     [](const DetectOptions& o) { return OptionValue(o.self); },
     [](DetectOptions& o, const OptionValue& v) { o.self = std::get<bool>(v); }},
    {"self_adjacency", "", "--self-adjacency",
     "Which triangles of one object are adjacent (never a self pair): index (they share a vertex index; default) or "
     "position (they share a vertex position: welds the seams of meshes with duplicated vertices)",
     K::choice, 0, 0, "", "index,position", "adjacency", kRecordedWhenSet,
     [](const DetectOptions& o) { return OptionValue(std::string(to_string(o.self_adjacency))); },
     [](DetectOptions& o, const OptionValue& v) { o.self_adjacency = *parse_self_adjacency(word(v)); }},
    {"max_contacts", "", "--max-contacts",
     "At most N contacts per object pair (0: every one; 1: a first-contact query): the pair's exact tests stop at "
     "the N-th colliding triangle pair",
     K::integer, 0, 1e9, "must be within 0..1000000000 (0 = every contact)", "", "", kRecordedWhenSet,
     [](const DetectOptions& o) { return OptionValue(double(o.max_contacts)); },
     [](DetectOptions& o, const OptionValue& v) { o.max_contacts = std::size_t(num(v)); }},
    {"contacts", "", "--contacts",
     "What each contact holds: segments (its exact intersection segment and kind; the default) or pairs (the "
     "colliding triangle pairs alone, the same exact answer: kind \"unclassified\", no segment, but for the contacts "
     "tested before an object pair's first crossing one, which decide its relation)",
     K::choice, 0, 0, "", "segments,pairs", "contact detail", kRecordedWhenSet,
     [](const DetectOptions& o) { return OptionValue(std::string(to_string(o.contacts))); },
     [](DetectOptions& o, const OptionValue& v) { o.contacts = *parse_contact_detail(word(v)); }},
    {"volume", "", "--volume",
     "The intersection volume of every pair of closed objects whose boxes overlap, with its error estimate and "
     "the direction that reduces it (rays over the overlap box; an open or inside-out object gets none, and why)",
     K::boolean, 0, 0, "must be true or false", "", "", kRecordedWhenSet,
     [](const DetectOptions& o) { return OptionValue(o.volume); },
     [](DetectOptions& o, const OptionValue& v) { o.volume = std::get<bool>(v); }},
    {"depth", "", "--depth",
     "A penetration direction n and depth d for every colliding or containing pair of closed objects: moving "
     "A by d n separates them (touching allowed), no shorter move along n does; the least d over the candidate "
     "directions of docs/design.md (an open or inside-out object gets none, and why)",
     K::boolean, 0, 0, "must be true or false", "", "", kRecordedWhenSet,
     [](const DetectOptions& o) { return OptionValue(o.depth); },
     [](DetectOptions& o, const OptionValue& v) { o.depth = std::get<bool>(v); }},
    {"margin", "", "--margin",
     "Proximity: every triangle pair of two objects (of one object with --self, not sharing a vertex) within "
     "this distance, with its distance and closest points, and per object pair the least distance and its "
     "witness points (default 0: off)",
     K::number, 0, kInf, "must be >= 0 (0 = off)", "", "", kRecordedWhenSet,
     [](const DetectOptions& o) { return OptionValue(o.margin); },
     [](DetectOptions& o, const OptionValue& v) { o.margin = num(v); }},
};

}  // namespace

const std::vector<OptionSpec>& option_table() { return kTable; }

const OptionSpec* find_option(std::string_view key) {
  for (const OptionSpec& s : kTable)
    if (key == s.key) return &s;
  return nullptr;
}

std::string check_option(const OptionSpec& spec, const OptionValue& value) {
  switch (spec.kind) {
    case K::boolean:
      return std::holds_alternative<bool>(value) ? std::string() : "must be true or false";
    case K::choice: {
      if (!std::holds_alternative<std::string>(value)) return "must be a string";
      if (!is_choice(spec.choices, word(value)))
        return std::string("unknown ") + spec.noun + " \"" + word(value) + "\" (expected " + choice_list(spec.choices) + ")";
      return {};
    }
    case K::integer:
    case K::number: {
      if (!std::holds_alternative<double>(value)) return "must be a number";
      const double x = num(value);
      // The value is printed only into a problem (every frame validates its options: a valid
      // one costs comparisons alone).
      const auto got = [x] {
        char text[48];
        std::snprintf(text, sizeof text, ", got %.17g", x);
        return std::string(text);
      };
      if (!std::isfinite(x)) return "must be finite" + got();
      if (spec.kind == K::integer && x != std::floor(x)) return "must be a whole number" + got();
      if (x < spec.min || x > spec.max) return spec.range + got();
      return {};
    }
  }
  return {};
}

OptionValue parse_option(const OptionSpec& spec, const std::string& text, std::string& problem) {
  problem.clear();
  switch (spec.kind) {
    case K::boolean:
      if (text == "true" || text == "1") return true;
      if (text == "false" || text == "0") return false;
      problem = "\"" + text + "\" is not true or false";
      return false;
    case K::choice:
      problem = check_option(spec, text);
      return text;
    case K::integer:
    case K::number: {
      char* end = nullptr;
      const double x = text.empty() ? 0.0 : std::strtod(text.c_str(), &end);
      if (text.empty() || end != text.c_str() + text.size()) {
        problem = "\"" + text + "\" is not a number";
      } else if (!std::isfinite(x)) {
        problem = "\"" + text + "\" is not a finite number";
      } else if (spec.kind == K::integer && x != std::floor(x)) {
        problem = "\"" + text + "\" is not an integer";
      } else {
        problem = check_option(spec, x);
      }
      return x;
    }
  }
  return {};
}

void set_option(DetectOptions& options, const OptionSpec& spec, const OptionValue& value, const std::string& where) {
  if (const std::string problem = check_option(spec, value); !problem.empty())
    throw std::invalid_argument(where + ": " + problem);
  spec.set(options, value);
}

bool sets_view_direction(const OptionSpec& spec) {
  return std::string_view(spec.key) == "theta" || std::string_view(spec.key) == "phi";
}

}  // namespace peelcd
