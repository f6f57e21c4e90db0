// lightvol: closed light volumes from shadow-map depth images. Parses the command line, runs
// one command from the library, and turns its errors into exit codes.
#include <cstdio>
#include <exception>
#include <new>
#include <string_view>
#include <utility>

#include <lightvol/core/limits.h>

#include "commands.h"

namespace lightvol::cli {

namespace {

// The library's names of the parameters a message may advise changing, and the flags that set
// them here. The library's tests assert that its messages use these names.
constexpr std::pair<std::string_view, std::string_view> kParameterFlags[] = {
    {"DepthReadOptions::channel", "--channel"},
    {"VolumeOptions::space = Space::light", "--space light"},
    {"ExportOptions::draco_bits", "--draco-bits"},
    {"CheckOptions::cgal_with_light", "--cgal"},
    {"set_memory_budget()", "--max-memory"},
    {"shadow_map_size(n)", "--size"},
    {"BuildFileOptions::light_path", "--light"},
    {"BuildFileOptions::out_path", "--out"},
    {"BuildFileOptions::report_path", "--report"},
    {"BuildFileOptions::medium_path", "--medium"},
    {"DemoOptions::data_dir", "--data"},
    {"RenderRequest::method", "--method"},
    {"BatchFiles::results_path", "--results"},
};

}  // namespace

std::string with_flags(std::string message) {
  for (const auto& [parameter, flag] : kParameterFlags)
    for (std::size_t at = message.find(parameter); at != std::string::npos;
         at = message.find(parameter, at + flag.size()))
      message.replace(at, parameter.size(), flag);
  return message;
}

std::string printable(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte != 0x7f) {
      out += c;
      continue;
    }
    char escaped[5];
    std::snprintf(escaped, sizeof escaped, "\\x%02x", byte);
    out += escaped;
  }
  return out;
}

std::string json_text(const nlohmann::json& j, int indent) {
  return j.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string json_text(const nlohmann::ordered_json& j, int indent) {
  return j.dump(indent, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
}

// The one place an error becomes an exit code (docs/design.md): 1 a volume that fails its checks,
// 2 anything else (bad usage or input, a volume float32 cannot hold, a refused read or write).
int exit_code(ErrorKind kind) { return kind == ErrorKind::unsound ? 1 : 2; }

int fail(const Error& error) {
  std::fprintf(stderr, "lightvol: %s\n", printable(with_flags(error.message)).c_str());
  return exit_code(error.kind);
}

int fail(const std::string& message) { return fail(Error{message}); }

}  // namespace lightvol::cli

int main(int argc, char** argv) {
  using namespace lightvol::cli;
  CLI::App app{
      "lightvol turns shadow-map depth images into closed light volumes: meshes enclosing exactly\n"
      "the space a light illuminates, for exact volumetric shadows drawn with additive "
      "blending.\n"};
  app.name("lightvol");
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("lightvol ") + kVersion);
  app.footer(
      "Run 'lightvol COMMAND --help' for a command's options. Exit codes: 0 success, "
      "1 invalid volume, 2 bad usage or input.");

  // --max-memory belongs to the app; fallthrough lets it follow any command (set before the
  // commands are added: subcommands inherit it).
  std::string max_memory;
  app.add_option("--max-memory", max_memory,
                 "Memory budget inputs are checked against before they are read, e.g. 8G "
                 "(default: 75% of physical memory)");
  app.fallthrough();

  Runner run;
  add_build_command(app, &run);
  add_batch_command(app, &run);
  add_stats_command(app, &run);
  add_check_command(app, &run);
  add_demo_command(app, &run);
#ifdef LIGHTVOL_HAS_SHADOWMAP
  add_shadowmap_command(app, &run);
#endif
  add_render_command(app, &run);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return fail(e.what() + std::string(" (see 'lightvol --help')"));
  }
  if (!max_memory.empty()) {
    const lightvol::Result<std::uint64_t> budget = lightvol::parse_memory_size(max_memory);
    if (!budget) return fail("--max-memory: " + budget.error().message);
    lightvol::set_memory_budget(*budget);
  }
  // No exception leaves a command: a library's exception here is a bug, said in one line (exit 2,
  // as docs/design.md says), never an abort.
  try {
    return run ? run() : 2;
  } catch (const std::bad_alloc&) {
    return fail("out of memory");
  } catch (const std::exception& e) {
    return fail(std::string("internal error: ") + e.what());
  } catch (...) {
    return fail("internal error: an unknown exception");
  }
}
