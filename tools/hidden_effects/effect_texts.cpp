#include "tools/hidden_effects/effect_texts.hpp"

#include "tools/hidden_effects/make_run.hpp"

namespace rigctl {

std::vector<std::pair<std::string, double>> parse_effect_texts(const std::vector<std::string>& texts) {
  std::vector<std::pair<std::string, double>> out;
  for (const auto& e : texts) {
    const auto colon = e.find(':');
    out.emplace_back(e.substr(0, colon), colon == std::string::npos ? 1.0 : parse_effect_level(e.substr(colon + 1)));
  }
  return out;
}

}  // namespace rigctl
