// `identify.excitation` of a config and `rigctl identify --excitation`: the
// band-limited signal added to the demand while the loop's frequency
// response is measured (tools/identify/excitation.hpp).
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

#include "config/kind_names.hpp"

namespace rigctl {

enum class ExcitationKind : uint8_t {
  kMultisine,  // Schroeder-phased lines on every frequency bin of the band, periodic in one segment
  kChirp,      // a linear sweep across the band, repeated once per segment
  kPinkNoise,  // Gaussian noise with 1/f power across the band (not periodic)
};

constexpr std::string_view to_string(ExcitationKind k) {
  switch (k) {
    case ExcitationKind::kMultisine: return "multisine";
    case ExcitationKind::kChirp: return "chirp";
    case ExcitationKind::kPinkNoise: return "pink_noise";
  }
  return "unknown";
}

template <>
struct KindNames<ExcitationKind> {
  static constexpr std::string_view noun = "excitation";
  static constexpr std::array known{ExcitationKind::kMultisine, ExcitationKind::kChirp, ExcitationKind::kPinkNoise};
};

}  // namespace rigctl
