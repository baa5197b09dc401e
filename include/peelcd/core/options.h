#pragma once
// Every option of a frame (DetectOptions, peelcd/core/frame.h), defined once: its key in scene
// files and in the JSON that records a frame, its command-line flag, its help, its kind and
// range. The scene reader (peelcd/io/scene.h), the JSON writer and reader
// (peelcd/io/options_json.h), the JSON Schema's list (docs/schema/result.schema.json, checked by
// a test), the command line and validate_options() (peelcd/core/image/detector.h) all derive from
// option_table(). Adding an option: a field in DetectOptions, a row here (docs/architecture.md).
#include "peelcd/core/frame.h"

#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace peelcd {

// An option's value: a flag, a number (integers too: checked integral), a word (choices).
using OptionValue = std::variant<bool, double, std::string>;

constexpr int kRecordedWhenSet = 2;

struct OptionSpec {
  enum class Kind { boolean, integer, number, choice };
  const char* key;    // scene file and JSON key, e.g. "theta"
  const char* group;  // "" or the scene object the key lives in ("view": view.theta)
  const char* flag;   // command-line flag, e.g. "--theta"; nullptr: none
  const char* help;   // one sentence for --help
  Kind kind;
  double min, max;      // integer and number: the accepted range, inclusive (finite values only)
  const char* range;    // the range in words, for messages: "must be >= 0 (0 = one texel)"
  const char* choices;  // choice: the words, comma-separated ("paper,ring,unique")
  const char* noun;     // choice: what a word names, for messages ("ID mode")
  int recorded;         // written where a frame is recorded (the result JSON, dumps): 1 always
                        // (every option a result depends on), 0 never (threads, on which no
                        // result depends), kRecordedWhenSet only when not the default (options
                        // added after goldens were recorded and off in them: self)
  // The effective value (edge_texels unset reads as the mode's default, edge_texels_of()).
  OptionValue (*get)(const DetectOptions&);
  void (*set)(DetectOptions&, const OptionValue&);  // takes a value check_option() accepted
};

// The options, in the order the JSON writes them.
const std::vector<OptionSpec>& option_table();
// The row of `key` ("theta"), or nullptr.
const OptionSpec* find_option(std::string_view key);

// Empty if `value` is of the spec's kind and within its range or choices, else the problem in
// words ("must be within [-90, 90]", "unknown ID mode \"fancy\" (expected unique, ring or paper)").
std::string check_option(const OptionSpec& spec, const OptionValue& value);
// Parses `text` (a command-line value) for `spec`: the value, or the problem in `problem`.
OptionValue parse_option(const OptionSpec& spec, const std::string& text, std::string& problem);
// Checks `value`, then sets it; throws std::invalid_argument("<where>: <problem>").
void set_option(DetectOptions& options, const OptionSpec& spec, const OptionValue& value, const std::string& where);

// The scene files' view rule, in one place: naming theta or phi (in a scene's "view", or on the
// command line) turns the paper's frame (roll 0) there unless roll is given too.
bool sets_view_direction(const OptionSpec& spec);

}  // namespace peelcd
