// Session settings between Python and the core: keyword arguments in, a dict of values and the
// settings table (surfeledit.core.setting_specs) out.
#include <cmath>
#include <string>
#include <variant>
#include <vector>

#include "surfeledit/core/settings.hpp"

#include "common.hpp"

namespace surfeledit::py {
namespace {

// A Python int as a setting value: the integer, or (beyond 64 bits) the number, which the core refuses.
SettingValue int_value(const pyb::handle& value) {
  int overflow = 0;
  const long long v = PyLong_AsLongLongAndOverflow(value.ptr(), &overflow);
  if (overflow == 0 && !(v == -1 && PyErr_Occurred())) return static_cast<std::int64_t>(v);
  PyErr_Clear();
  return pyb::cast<double>(value);
}

// A setting value as Python bool, int, float or str.
pyb::object py_value(const SettingValue& v) {
  return std::visit([](const auto& x) -> pyb::object { return pyb::cast(x); }, v);
}

// A bound of a Number/Integer setting: None when open, int for an integer setting.
pyb::object py_bound(const SettingSpec& spec, double bound) {
  if (!std::isfinite(bound)) return pyb::none();
  if (spec.kind == SettingType::Integer) return pyb::int_(static_cast<long long>(bound));
  return pyb::float_(bound);
}

// The settings table for Python: one dict per setting, in listing order.
pyb::list specs_list() {
  pyb::list out;
  for (const SettingSpec& spec : setting_specs()) {
    pyb::dict d;
    d["name"] = spec.name;
    d["kind"] = enum_name(spec.kind);
    d["default"] = py_value(default_value(spec));
    d["min"] = py_bound(spec, spec.min);
    d["max"] = py_bound(spec, spec.max);
    d["min_exclusive"] = spec.min_open;
    d["expects"] = expected_value(spec);
    d["choices"] = pyb::cast(std::vector<std::string>(spec.choices.begin(), spec.choices.end()));
    d["doc"] = spec.doc;
    out.append(d);
  }
  return out;
}

}  // namespace

// Keyword arguments -> settings: bool -> bool, int -> integer, float -> number, str -> text.
std::vector<NamedSetting> to_settings(const pyb::kwargs& kwargs) {
  std::vector<NamedSetting> out;
  for (const auto& [key, value] : kwargs) {
    const std::string name = pyb::cast<std::string>(key);
    if (pyb::isinstance<pyb::bool_>(value)) {
      out.push_back({name, pyb::cast<bool>(value)});
    } else if (pyb::isinstance<pyb::int_>(value)) {
      out.push_back({name, int_value(value)});
    } else if (pyb::isinstance<pyb::float_>(value)) {
      out.push_back({name, pyb::cast<double>(value)});
    } else if (pyb::isinstance<pyb::str>(value)) {
      out.push_back({name, pyb::cast<std::string>(value)});
    } else {
      throw Error(ErrorCode::InvalidArgument, name,
                  "expects a bool, number or str, got " + std::string(pyb::str(pyb::type::handle_of(value).attr("__name__"))));
    }
  }
  return out;
}

pyb::dict settings_dict(const SessionSettings& settings) {
  pyb::dict d;
  for (const NamedSetting& s : describe(settings)) d[pyb::str(s.name)] = py_value(s.value);
  return d;
}

// The docstring of EditSession.configure: one line per setting of the table.
const char* configure_doc() {
  static const std::string doc = [] {
    std::string out = "Session settings by keyword, validated before anything changes (all or none):\n";
    for (const SettingSpec& spec : setting_specs()) {
      out += "  " + std::string(spec.name) + ": " + spec.doc + "; " + expected_value(spec) + ", default " +
             pyb::repr(py_value(default_value(spec))).cast<std::string>() + "\n";
    }
    return out;
  }();
  return doc.c_str();
}

void bind_settings(pyb::module_& m) {
  m.def("setting_specs", &specs_list,
        "The session settings table: one dict per setting (name, kind 'number'|'integer'|'bool'|'text', default, "
        "min, max (None: open), min_exclusive, choices, expects, doc), in the order settings() lists them");
}

}  // namespace surfeledit::py
