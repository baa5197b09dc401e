// peelcd: image-space collision detection through alternate surface peeling. The command
// line: each command in its own file (apps/cmd_*.cpp), what they share in apps/cli.h.
#include "cli.h"
#include "peelcd/gl/context.h"
#include "peelcd/version.h"

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace peelcd::cli {
namespace {

// Help that reads as words: CLI11 writes an option's type and each validator joined by ':'
// ("INT:INT in [0 - 64]", "FLOAT:FINITE:FLOAT in [-90 - 90]"); this writes "INT in [0, 64]",
// "FLOAT in [-90, 90]", "INT > 0", "FLOAT >= 0", "{1,2,3}".
class HelpFormatter : public CLI::Formatter {
 public:
  std::string make_option_opts(const CLI::Option* opt) const override {
    std::string s = CLI::Formatter::make_option_opts(opt);
    const auto replace_all = [&](const std::string& from, const std::string& to) {
      for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) s.replace(at, from.size(), to);
    };
    for (const char* type : {"INT", "FLOAT", "UINT"}) {
      const std::string t = type;
      replace_all(t + ":FINITE:" + t + " in ", t + " in ");
      replace_all(t + ":" + t + " in ", t + " in ");
      replace_all(t + ":FINITE", t);
      replace_all(t + ":POSITIVE", t + " > 0");
      replace_all(t + ":NONNEGATIVE", t + " >= 0");
      replace_all(t + ":{", "{");
    }
    // "[0 - 64]" -> "[0, 64]"
    for (std::size_t open = s.find('['); open != std::string::npos; open = s.find('[', open + 1)) {
      const std::size_t close = s.find(']', open), dash = s.find(" - ", open);
      if (close != std::string::npos && dash != std::string::npos && dash < close) s.replace(dash, 3, ", ");
    }
    return s;
  }
};

}  // namespace
}  // namespace peelcd::cli

using namespace peelcd;
using namespace peelcd::cli;

int main(int argc, char** argv) {
  CLI::App app{"peelcd: image-space collision detection between triangle meshes through "
               "alternate surface peeling (OSMesa reference backend)"};
  app.set_version_flag("--version", std::string("peelcd ") + PEELCD_VERSION_STRING);
  app.formatter(std::make_shared<HelpFormatter>());  // subcommands inherit it
  app.require_subcommand(1);
  std::vector<Command> commands;
  for (auto add : {add_detect_commands, add_dump_commands, add_golden_commands, add_simulate_commands,
                   add_bench_commands, add_sweep_commands, add_eval_commands})
    for (Command& c : add(app)) commands.push_back(std::move(c));

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kExitBadInput;
  }
  // What a command printed must have reached its destination (`> /dev/full`, a closed pipe):
  // a failed write is an error, not a success.
  const auto flushed = [](int rc) {
    if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
      std::fprintf(stderr, "error: peelcd: writing the standard output failed: %s\n", std::strerror(errno));
      return rc ? rc : kExitBadInput;
    }
    return rc;
  };
  try {
    for (const Command& c : commands)  // in registration order: a sub-subcommand before its parent
      if (*c.app) return flushed(c.run());
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
