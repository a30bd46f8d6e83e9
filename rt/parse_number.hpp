// Numbers typed by a person (command-line specs, effect levels): the whole
// text must be one finite number. Config files go through ConfigReader.
#pragma once

#include <cmath>
#include <optional>
#include <string>

namespace rigctl {

// std::nullopt for an empty text, trailing characters, inf, nan or a value
// out of double's range.
inline std::optional<double> parse_finite(const std::string& text) {
  std::size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (used == 0 || used != text.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

}  // namespace rigctl
