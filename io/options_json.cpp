#include "peelcd/io/options_json.h"

#include "peelcd/core/options.h"

#include <stdexcept>

namespace peelcd {

namespace {
// Integers as JSON integers, numbers as JSON numbers (31.0 stays 31.0).
nlohmann::json option_json(const OptionSpec& spec, const OptionValue& v) {
  if (const bool* b = std::get_if<bool>(&v)) return *b;
  if (const double* d = std::get_if<double>(&v)) {
    if (spec.kind == OptionSpec::Kind::integer) return static_cast<long long>(*d);
    return *d;
  }
  return std::get<std::string>(v);
}
}  // namespace

nlohmann::json options_to_json(const DetectOptions& o) {
  nlohmann::json out = nlohmann::json::object();
  const DetectOptions defaults;
  for (const OptionSpec& spec : option_table()) {
    if (!spec.recorded) continue;
    if (spec.recorded == kRecordedWhenSet && spec.get(o) == spec.get(defaults)) continue;
    out[spec.key] = option_json(spec, spec.get(o));
  }
  return out;
}

DetectOptions options_from_json(const nlohmann::json& j) {
  if (!j.is_object()) throw std::invalid_argument("options: must be an object");
  DetectOptions o;
  for (const auto& [key, value] : j.items()) {
    const OptionSpec* spec = find_option(key);
    if (!spec) throw std::invalid_argument("options: unknown key \"" + key + "\"");
    OptionValue v;
    if (value.is_boolean()) v = value.get<bool>();
    else if (value.is_number()) v = value.get<double>();
    else if (value.is_string()) v = value.get<std::string>();
    else throw std::invalid_argument("options." + key + ": must be a boolean, a number or a string");
    set_option(o, *spec, v, "options." + key);
  }
  return o;
}

nlohmann::json gl_options_to_json(const gl::GlOptions& o) {
  nlohmann::json out = nlohmann::json::object();
  for (const gl::GlOptionSpec& spec : gl::gl_option_table()) {
    const std::string v = spec.get(o);
    if (*spec.choices) out[spec.key] = v;
    else out[spec.key] = v == "true";
  }
  return out;
}

gl::GlOptions gl_options_from_json(const nlohmann::json& j) {
  if (!j.is_object()) throw std::invalid_argument("gl_options: must be an object");
  gl::GlOptions o;
  for (const auto& [key, value] : j.items()) {
    std::string words;
    if (value.is_boolean()) words = value.get<bool>() ? "true" : "false";
    else if (value.is_string()) words = value.get<std::string>();
    else throw std::invalid_argument("gl_options." + key + ": must be a string or a boolean");
    const std::string problem = gl::set_gl_option(o, key, words);
    if (!problem.empty()) throw std::invalid_argument("gl_options: " + problem);
  }
  return o;
}

}  // namespace peelcd
