// Session settings by name: the names the protocol's OP_CONFIGURE and the Python keyword
// arguments use (`session.configure(algorithm="robust", boundary_n=10, ...)`).
//
// Every setting is one row of one table (setting_specs(), settings.cpp): its name, kind, accepted
// range or names, one-line doc, and where it lives in SessionSettings. The table drives applying
// and checking a change, describe(), the unknown-name message, the Python keyword docs
// (`surfeledit.core.setting_specs()`) and the protocol's SettingKind. Defaults are the member
// initialisers of the parameter structs (a row's default is its value in `SessionSettings{}`).
#pragma once

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "surfeledit/core/collision.hpp"
#include "surfeledit/core/edit_params.hpp"
#include "surfeledit/core/enum_names.hpp"
#include "surfeledit/core/particles/blend.hpp"
#include "surfeledit/core/resampling.hpp"
#include "surfeledit/core/simplify/params.hpp"

namespace surfeledit {

struct SessionSettings {
  CollisionParams collision;
  ResampleParams resample;
  HierarchyParams hierarchy;
  SimplifyParams simplify = no_simplification();  // clustering (approximate detection when method != None;
                                                  // cluster_size / max_variation also shape sphere_* trees)
  ResponseParams response;  // what a colliding step does (report, cancel, backoff)
  HistoryParams history;    // the undo history's memory bound
  BlendSettings blend;      // the blend tool (particles/blend.hpp)

  static SimplifyParams no_simplification() {
    SimplifyParams p;
    p.method = SimplifyMethod::None;
    return p;
  }
};

// A setting's value as it arrives or is listed: number, integer, bool or text. An integer setting
// also accepts a number with an integral value (older protocol clients send integers as numbers);
// a number setting also accepts an integer.
using SettingValue = std::variant<double, std::int64_t, bool, std::string>;
struct NamedSetting {
  std::string name;
  SettingValue value;
};

// What a setting holds (the protocol's SettingKind, the Python type).
enum class SettingType : std::uint8_t {
  Number = 0,   // finite double (model units where it is a length)
  Integer = 1,  // int
  Bool = 2,
  Text = 3,     // one of the names of an enum (SettingSpec::choices)
};
constexpr EnumNames<SettingType, 4> names_of(SettingType) {
  return {{{SettingType::Number, "number"},
           {SettingType::Integer, "integer"},
           {SettingType::Bool, "bool"},
           {SettingType::Text, "text"}}};
}

// One row of the settings table.
struct SettingSpec {
  const char* name;                  // as in OP_CONFIGURE and the Python keywords
  SettingType kind;                  // what the value is
  const char* doc;                   // one line, with units
  double min;                        // Number/Integer: smallest accepted value (-inf: none)
  double max;                        // Number/Integer: largest accepted value (+inf: none)
  bool min_open;                     // `min` itself is refused (e.g. split_threshold > 1)
  std::vector<const char*> choices;  // Text: the accepted names, in enum order
  SettingValue (*get)(const SessionSettings&);                // the current value, of `kind`
  void (*set)(SessionSettings&, const SettingValue& checked);  // stores a value check_setting() accepted
};

// Every setting, in listing order.
const std::vector<SettingSpec>& setting_specs();

// The value of `spec` in a default-constructed SessionSettings.
SettingValue default_value(const SettingSpec& spec);

// What `spec` accepts, as its error messages say it: "an integer >= 1", "a finite number in [0, 1]",
// "a bool", "one of lite, full".
std::string expected_value(const SettingSpec& spec);

// Applies `changes` to a copy of `current` and validates the result. Throws InvalidArgument naming
// the setting (field = its name) for an unknown name, a value of the wrong kind (e.g. text for
// boundary_n, 2.5 for an int), a value out of its range or an unknown name of a text setting; then,
// naming one of the settings involved, for a combination that cannot run (e.g. boundary_i >
// boundary_n, extended without robust). `current` is never modified.
SessionSettings apply_settings(const SessionSettings& current, const std::vector<NamedSetting>& changes);

// Every setting with its current value, in table order; integers as std::int64_t.
std::vector<NamedSetting> describe(const SessionSettings& settings);

}  // namespace surfeledit
