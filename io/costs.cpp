#include "peelcd/io/costs.h"

#include "peelcd/io/error.h"
#include "peelcd/io/output.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace peelcd {

namespace {
double coefficient(const nlohmann::json& model, const char* key, const std::string& where) {
  if (!model.contains(key)) return 0.0;
  const nlohmann::json& v = model.at(key);
  if (!v.is_number() || !std::isfinite(v.get<double>()) || v.get<double>() < 0.0)
    throw InputError(where + "." + key + ": must be a finite number >= 0");
  return v.get<double>();
}
}  // namespace

CostModels read_cost_models(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError("peelcd: cost models '" + path + "': cannot open the file");
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text.str());
  } catch (const nlohmann::json::exception& e) {
    throw InputError("peelcd: cost models '" + path + "': malformed JSON: " + e.what());
  }
  const std::string where = "peelcd: cost models '" + path + "'";
  if (!j.is_object() || j.value("format", std::string()) != kCostsFormat)
    throw InputError(where + ": not a " + std::string(kCostsFormat) + " file (written by peelcd calibrate --write-costs)");
  for (const char* key : {"backend", "renderer"})
    if (!j.contains(key) || !j.at(key).is_string()) throw InputError(where + ": \"" + key + "\" must be a string");
  for (const char* key : {"image", "exact"})
    if (!j.contains(key) || !j.at(key).is_object()) throw InputError(where + ": \"" + key + "\" must be an object");
  CostModels m;
  m.source = path;
  m.backend = j.at("backend").get<std::string>();
  m.renderer = j.at("renderer").get<std::string>();
  if (j.contains("coverage")) {
    const nlohmann::json& c = j.at("coverage");
    if (!c.is_string() || (c.get<std::string>() != "raster" && c.get<std::string>() != "compute"))
      throw InputError(where + ": \"coverage\" must be \"raster\" or \"compute\"");
    m.coverage = c.get<std::string>();
  }
  const nlohmann::json &image = j.at("image"), &exact = j.at("exact");
  m.image = StageCost{coefficient(image, "view_ms", where + ": image"), coefficient(image, "triangle_us", where + ": image"),
                      coefficient(image, "texel_ns", where + ": image"), coefficient(image, "scan_us", where + ": image")};
  m.exact = StageCost{coefficient(exact, "view_ms", where + ": exact"), coefficient(exact, "triangle_us", where + ": exact"),
                      0.0, coefficient(exact, "scan_us", where + ": exact")};
  return m;
}

void write_cost_models(const std::string& path, const CostModels& m, const std::string& fitted) {
  nlohmann::json j = {
      {"format", kCostsFormat},
      {"backend", m.backend},
      {"renderer", m.renderer},
      {"fitted", fitted},
      {"image", {{"view_ms", m.image.view_ms}, {"triangle_us", m.image.triangle_us}, {"texel_ns", m.image.texel_ns},
                 {"scan_us", m.image.scan_us}}},
      {"exact", {{"view_ms", m.exact.view_ms}, {"triangle_us", m.exact.triangle_us}, {"scan_us", m.exact.scan_us}}}};
  if (!m.coverage.empty()) j["coverage"] = m.coverage;
  write_output_file(path, j.dump(2) + "\n", "peelcd calibrate: --write-costs");
}

void apply_cost_models(ImageStage& stage, const std::string& path) {
  const CostModels m = read_cost_models(path);
  if (m.backend != stage.backend() || m.renderer != stage.renderer())
    throw InputError("peelcd: cost models '" + path + "' were fitted on " + m.backend + " (\"" + m.renderer +
                     "\"), this stage is " + stage.backend() + " (\"" + stage.renderer() +
                     "\"): run peelcd calibrate --write-costs on this one");
  stage.set_cost_models(m);
}

std::string apply_cost_models_from_env(ImageStage& stage) {
  const char* path = std::getenv("PEELCD_COSTS");
  if (!path || !*path) return {};
  apply_cost_models(stage, path);
  return path;
}

}  // namespace peelcd
