// The hidden effects asked for on a command line (`rigctl make-run --effect`,
// `rigctl iterate --effect`): CAUSE[:weak|strong|LEVEL] each.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace rigctl {

// (cause, level) per text, the level 1 (strong) where none is given; throws
// std::invalid_argument naming a bad level (parse_effect_level).
std::vector<std::pair<std::string, double>> parse_effect_texts(const std::vector<std::string>& texts);

}  // namespace rigctl
