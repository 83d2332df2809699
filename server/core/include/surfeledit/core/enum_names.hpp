// Names of enum values, one table per enum, for parsing and printing (settings, protocol, bindings).
//
// The contract: next to an enum E, in E's namespace, a constexpr function
//
//   constexpr EnumNames<Blend, 3> names_of(Blend) {
//     return {{{Blend::Smooth, "smooth"}, {Blend::Quadratic, "quadratic"}, {Blend::Linear, "linear"}}};
//   }
//
// lists every value with its name (found by argument-dependent lookup). Then parse_enum<E>(),
// enum_name() and enum_choices<E>() work for E; nothing else is written per enum.
#pragma once

#include <array>
#include <cstddef>
#include <string>

namespace surfeledit {

template <typename E>
struct EnumName {
  E value;           // the enumerator
  const char* name;  // its name in settings, the protocol and Python
};
template <typename E, std::size_t N>
using EnumNames = std::array<EnumName<E>, N>;

// Every value of E with its name, in declaration order.
template <typename E>
constexpr auto enum_names() {
  return names_of(E{});
}

// The name of `value`; "unknown" for a value outside the table.
template <typename E>
const char* enum_name(E value) {
  for (const EnumName<E>& n : enum_names<E>())
    if (n.value == value) return n.name;
  return "unknown";
}

// "a, b, c": every name of E, for messages and documentation.
template <typename E>
std::string enum_choices() {
  std::string out;
  for (const EnumName<E>& n : enum_names<E>()) out += (out.empty() ? "" : ", ") + std::string(n.name);
  return out;
}

// Throws Error(InvalidArgument, field, "unknown value 'name'; expected one of <choices>").
[[noreturn]] void throw_unknown_name(const std::string& field, const std::string& name, const std::string& choices);

// The value named `name`; throws InvalidArgument naming `field` for any other name.
template <typename E>
E parse_enum(const std::string& name, const std::string& field) {
  for (const EnumName<E>& n : enum_names<E>())
    if (name == n.name) return n.value;
  throw_unknown_name(field, name, enum_choices<E>());
}

}  // namespace surfeledit
