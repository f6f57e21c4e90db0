// The numeric flags' validators (commands.h): one reading of a number for every command.
#include <cstdio>
#include <string>

#include <lightvol/core/text.h>

#include "commands.h"

namespace lightvol::cli {
namespace {

std::string shown(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", x);
  return text;
}

CLI::Validator number_validator(bool bounded, double min) {
  const std::string rule = "expected a finite number" + (bounded ? " >= " + shown(min) : "") +
                           " in decimal digits, got '";
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        const std::optional<double> v = parse_decimal(text);
        if (!v || (bounded && *v < min)) return rule + text + "'";
        return {};
      },
      bounded ? "NUMBER>=" + shown(min) : "NUMBER");
}

}  // namespace

CLI::Validator decimal_number() { return number_validator(false, 0); }

CLI::Validator decimal_number(double min) { return number_validator(true, min); }

CLI::Validator decimal_integer() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        if (!parse_decimal_integer(text))
          return "expected a whole number in decimal digits, got '" + text + "'";
        return {};
      },
      "INT");
}

}  // namespace lightvol::cli
