// Kinds are enums; their text names are contracts (YAML configs, run files,
// JSON, telemetry, command lines: docs/run-files.md) and stay as they are.
// Each kind has one exhaustive `to_string` beside its enum (the compiler
// flags a new enumerator without a name) and a KindNames specialisation:
// what the kind is called in messages and which enumerators a text may name.
// Every kind is parsed, and every unknown name refused with the known ones
// listed, by the functions below: one way for all of them.
#pragma once

#include <concepts>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>

namespace rigctl {

// Specialised beside each kind enum:
//   static constexpr std::string_view noun;  // "controller": "unknown controller 'pid'"
//   static constexpr std::array known;       // the enumerators a text may name, in the order messages list them
template <typename Kind>
struct KindNames;

template <typename Kind>
concept NamedKind = std::is_enum_v<Kind> && requires(Kind k) {
  { KindNames<Kind>::noun } -> std::convertible_to<std::string_view>;
  { KindNames<Kind>::known.size() } -> std::convertible_to<std::size_t>;
  { to_string(k) } -> std::convertible_to<std::string_view>;
};

// The kind whose name is `text`; empty for an unknown name.
template <NamedKind Kind>
constexpr std::optional<Kind> kind_from_string(std::string_view text) {
  for (const Kind k : KindNames<Kind>::known) {
    if (to_string(k) == text) return k;
  }
  return std::nullopt;
}

// The known names, comma-separated: "pi, pvp, passive, fuzzy, skyhook, lqr".
template <NamedKind Kind>
std::string known_kind_names() {
  std::string list;
  for (const Kind k : KindNames<Kind>::known) {
    if (!list.empty()) list += ", ";
    list += to_string(k);
  }
  return list;
}

// "unknown controller 'pid' (known: pi, pvp, passive, fuzzy, skyhook, lqr)"
template <NamedKind Kind>
std::string unknown_kind_message(std::string_view text) {
  return "unknown " + std::string(KindNames<Kind>::noun) + " '" + std::string(text) + "' (known: " +
         known_kind_names<Kind>() + ")";
}

// A kind named on a command line or by another program; throws
// std::invalid_argument with unknown_kind_message for an unknown name.
template <NamedKind Kind>
Kind parse_kind(std::string_view text) {
  if (const auto k = kind_from_string<Kind>(text)) return *k;
  throw std::invalid_argument(unknown_kind_message<Kind>(text));
}

// Kinds print by their names (console lines, test failures).
template <NamedKind Kind>
std::ostream& operator<<(std::ostream& out, Kind k) {
  return out << to_string(k);
}

}  // namespace rigctl
