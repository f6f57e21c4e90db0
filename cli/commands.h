// Each command registers a CLI11 subcommand and the function that runs it, returning the exit
// code: 0 success, 1 an invalid volume, 2 bad usage or input.
#pragma once

#include <functional>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <lightvol/core/result.h>

namespace lightvol::cli {

using Runner = std::function<int()>;

// The version `--version` prints and batch records in its job hashes (CMake's project version).
inline constexpr const char* kVersion = LIGHTVOL_VERSION;

void add_build_command(CLI::App& app, Runner* run);
void add_batch_command(CLI::App& app, Runner* run);
void add_stats_command(CLI::App& app, Runner* run);
void add_check_command(CLI::App& app, Runner* run);
void add_demo_command(CLI::App& app, Runner* run);
void add_shadowmap_command(CLI::App& app, Runner* run);  // with LIGHTVOL_HAS_SHADOWMAP
void add_render_command(CLI::App& app, Runner* run);

// A library message as this command line says it: the library names its own parameters
// (ExportOptions::draco_bits, set_memory_budget(), ...); here each becomes the flag that sets it
// (--draco-bits, --max-memory, ...).
std::string with_flags(std::string message);

// The exit code of an error of `kind`: 1 an unsound volume, 2 the other kinds. Defined once, in
// main.cpp.
int exit_code(ErrorKind kind);

// Prints "lightvol: <message>" on stderr, one line (printable, with_flags), and returns its
// kind's exit code.
int fail(const Error& error);
// The same for bad usage or input (exit 2).
int fail(const std::string& message);

// `text` safe for a terminal line: control characters (line breaks, escapes, NUL), which a
// message may quote from a hostile file, are written as \xNN.
std::string printable(const std::string& text);

// `j` as JSON text (`indent` as nlohmann's dump: -1 one line), valid UTF-8 whatever bytes its
// strings hold: every report, --json and result line is made here. A byte that is not part of
// valid UTF-8 (a Latin-1 file name) is written as U+FFFD, the replacement character
// (docs/formats.md, "Text in JSON outputs").
std::string json_text(const nlohmann::json& j, int indent = -1);
std::string json_text(const nlohmann::ordered_json& j, int indent = -1);

// Validators for every numeric flag: the text is read by core/text.h's one rule (parse_decimal,
// parse_decimal_integer: decimal only, so 0x10, inf, nan, " 3" and +3 are refused) before CLI11
// converts it, and the refusal names the flag ("--max-error: expected a finite number >= 0 in
// decimal digits, got '0x10'").
CLI::Validator decimal_number();            // a finite number
CLI::Validator decimal_number(double min);  // a finite number >= min
CLI::Validator decimal_integer();           // a whole number (bounds: add CLI::Range)

}  // namespace lightvol::cli
