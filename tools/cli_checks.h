// Number checks for the command-line tools, with messages a user can act on. CLI11's own
// PositiveNumber / NonNegativeNumber say "Value -1 not in range 0.000000 to 1797693134862315...
// (309 digits)"; these say "--duration: must be greater than 0, not -1".
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <string>

namespace lanemap::cli {

namespace detail {
inline CLI::Validator numberCheck(bool allow_zero) {
  return CLI::Validator(
      [allow_zero](std::string& text) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v)) return "a number is needed, not '" + text + "'";
        if (allow_zero ? v >= 0.0 : v > 0.0) return {};
        return std::string(allow_zero ? "must be 0 or more" : "must be greater than 0") + ", not " + text;
      },
      allow_zero ? ">= 0" : "> 0", allow_zero ? "NONNEGATIVE" : "POSITIVE");
}
}  // namespace detail

inline const CLI::Validator kPositive = detail::numberCheck(false);
inline const CLI::Validator kNonNegative = detail::numberCheck(true);

}  // namespace lanemap::cli
