// JSON scalars as text, for the commands that write their results by hand
// (diagnose, compare, optimize): one escaping and one number format.
#pragma once

#include <string>

namespace rigctl {

// A quoted JSON string; quotes, backslashes and control characters escaped.
std::string json_string(const std::string& s);
// A number with 10 significant digits; NaN and infinities become null
// (JSON has no such numbers).
std::string json_number(double v);

}  // namespace rigctl
