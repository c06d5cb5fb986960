#pragma once
/// \file
/// Every setting declared once (issue 31). A settings struct's description lists its fields, each
/// with its name, type, unit, default (read from the description's default struct, never a second
/// literal), range or choices, help, the settings it needs (the "does nothing here" refusals), and
/// its name at each edge: the command-line flag, the experiment-config (TOML) key and the Python
/// attribute. The edges are generated from it:
///   - the command line (CLI11): experiments/cli/settings_cli.hpp;
///   - the experiment configs (TOML): experiments/runner/settings_config.hpp;
///   - Python (pybind11): python/settings_python.hpp;
///   - the reference page docs/settings.md (`plydem settings`): experiments/runner/
///     settings_reference.hpp.
/// The descriptions themselves are in experiments/runner/settings_descriptions.hpp.
///
/// Values. Inside the struct (and in Python) numbers are in SI units (m, rad, Pa); on the command
/// line and in configs in the setting's edge unit (mm, deg), converted by SettingUnit at the edge,
/// as the code before the descriptions converted them (so that results keep their bits). A setting
/// that is not at one edge says why (no_flag, no_key, no_python): the exceptions are explicit.
///
/// Conditions. `only_if(holds, reason)`: given where `holds` is false, the setting "does nothing
/// here: <reason>"; `needs(holds, reason)`: "<setting> needs <reason>". A reason names other
/// settings as {name} (rendered as each edge names them: `--layup`, `layup`) or {name=value}
/// (`--solver explicit`, `solver = "explicit"`).

#include <deque>
#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "core/error.hpp"

namespace plydem {

enum class SettingType {
  kSwitch,   ///< true or false (a command-line flag without a value)
  kInteger,  ///< a whole number
  kNumber,   ///< a real number
  kText,     ///< a word or a name
  kTexts,    ///< a list of words (a repeatable command-line option)
};
/// "switch", "integer", "number", "text", "list of texts".
const char* setting_type_name(SettingType type);

/// A setting's value: numbers in the struct's units; monostate: unset (an optional setting).
using SettingValue =
    std::variant<std::monostate, bool, long, double, std::string, std::vector<std::string>>;

/// How a number reads at the edges that take it in other units than the struct's (the command line
/// and configs: mm, deg), and its unit there and in SI.
struct SettingUnit {
  std::string edge;                   ///< "mm", "deg", "Pa", "" (none)
  std::string si;                     ///< "m", "rad", "Pa", ""
  double (*to_si)(double) = nullptr;  ///< edge -> SI; nullptr: the same number
  double (*from_si)(double) = nullptr;
  double edge_to_si(double x) const { return to_si != nullptr ? to_si(x) : x; }
  double si_to_edge(double x) const { return from_si != nullptr ? from_si(x) : x; }
};

namespace setting_units {
/// The same number at every edge, in `symbol` ("Pa", "N/m^3", "" for none).
SettingUnit same(const std::string& symbol = "");
/// Millimetres at the edges, metres inside: x * 1e-3 (kMetresPerMm), as plydem always converted.
SettingUnit millimetres();
/// Millimetres per second at the edges, m/s inside.
SettingUnit millimetres_per_second();
/// Degrees at the edges, radians inside: x * pi / 180.0 (the command line's conversion).
SettingUnit degrees();
}  // namespace setting_units

/// Where a setting is set, for the names in messages.
enum class SettingEdge { kCommandLine, kConfig, kPython, kReference };

/// Everything about a setting but its struct: names, type, unit, help, choices, range.
struct SettingInfo {
  std::string name;  ///< the setting's own name (snake_case), used by conditions' {name}
  SettingType type = SettingType::kNumber;
  std::string flag;       ///< "--length-mm"; "" = not on the command line (no_flag says why)
  std::string key;        ///< "coupon.length_mm"; "" = not in configs (no_key says why)
  std::string quick_key;  ///< "quick.length_mm": replaces `key` in a quick run; "" = none
  std::string python;     ///< "coupon.length" (dotted: an attribute of an attribute); "" = none
  std::string no_flag, no_key, no_python;  ///< why the setting is not at that edge
  SettingUnit unit;
  /// What it does; its unit where {unit} stands (else after it), as each edge names the unit.
  std::string help;
  /// The values a text takes (read when asked, so that a list such as backend_choices() is never
  /// copied); empty function: any value.
  std::function<std::vector<std::string>()> choices;
  /// The command line checks the choices itself (CLI11's IsMember, which lists them in --help);
  /// false: the setter's parser names a bad one (as for --linear-solver).
  bool cli_checks_choices = true;
  /// Configs and Python leave a bad choice to the setter's parser, whose message they keep.
  bool setter_checks_choices = false;
  std::optional<double> min, max;  ///< in edge units, checked at every edge
  /// A range the struct's own validate() checks (with its own words), for the reference page.
  std::string validated_range;
  bool finite = false;  ///< refuse NaN and infinities at the edges ("--angle is not a finite ...")
  long integer_min = std::numeric_limits<long>::lowest();  ///< the member's own limits (integers)
  long integer_max = std::numeric_limits<long>::max();
  bool optional = false;  ///< may be unset (monostate): unset means `unset`
  std::string unset;      ///< "the material's"
  /// A switch whose command-line and config value is the negation of the struct's and Python's
  /// (--raw-edges against complete_boundary_cells).
  bool edge_inverts = false;
  /// Python's attribute is the struct's own member in its own type, bound by hand (a Material, a
  /// list of radians): python_type says what it takes.
  bool python_native = false;
  std::string python_type;
  bool show_default = true;  ///< the command line's --help shows the default
  /// Command-specific help added after `help` (for `plydem calibrate`), by command name.
  std::vector<std::pair<std::string, std::string>> command_notes;
};

/// One setting of a settings struct S: its info, its accessors (values in SI) and its conditions.
template <class S>
struct SettingField : SettingInfo {
  struct Condition {
    std::function<bool(const S&)> holds;
    std::string reason;  ///< with {name} and {name=value} placeholders
    bool needs = false;  ///< "X needs <reason>" instead of "X does nothing here: <reason>"
  };
  std::function<SettingValue(const S&)> get;
  /// Sets the value (SI); `what` names the setting in errors ("--strategy-option",
  /// "file.toml: strategy_options").
  std::function<void(S&, const SettingValue&, const std::string& what)> set;
  std::vector<Condition> conditions;

  SettingField& with_flag(std::string f) {
    flag = std::move(f);
    return *this;
  }
  SettingField& with_key(std::string k) {
    key = std::move(k);
    return *this;
  }
  SettingField& with_quick_key(std::string k) {
    quick_key = std::move(k);
    return *this;
  }
  SettingField& with_python(std::string p) {
    python = std::move(p);
    return *this;
  }
  SettingField& without_flag(std::string why) {
    no_flag = std::move(why);
    return *this;
  }
  SettingField& without_key(std::string why) {
    no_key = std::move(why);
    return *this;
  }
  SettingField& without_python(std::string why) {
    no_python = std::move(why);
    return *this;
  }
  SettingField& with_unit(SettingUnit u) {
    unit = std::move(u);
    return *this;
  }
  SettingField& with_help(std::string h) {
    help = std::move(h);
    return *this;
  }
  SettingField& with_choices(std::function<std::vector<std::string>()> c) {
    choices = std::move(c);
    return *this;
  }
  SettingField& with_choices(std::vector<std::string> c) {
    choices = [c] { return c; };
    return *this;
  }
  SettingField& parsed_by_setter(bool on_command_line_too) {
    setter_checks_choices = true;
    cli_checks_choices = !on_command_line_too;
    return *this;
  }
  SettingField& at_least(double m) {
    min = m;
    return *this;
  }
  SettingField& at_most(double m) {
    max = m;
    return *this;
  }
  SettingField& validated(std::string range) {
    validated_range = std::move(range);
    return *this;
  }
  SettingField& must_be_finite() {
    finite = true;
    return *this;
  }
  SettingField& unset_means(std::string what) {
    optional = true;
    unset = std::move(what);
    return *this;
  }
  SettingField& inverted_at_edges() {
    edge_inverts = true;
    return *this;
  }
  SettingField& python_as(std::string type) {
    python_native = true;
    python_type = std::move(type);
    return *this;
  }
  SettingField& hide_default() {
    show_default = false;
    return *this;
  }
  SettingField& note(std::string command, std::string text) {
    command_notes.emplace_back(std::move(command), std::move(text));
    return *this;
  }
  SettingField& only_if(std::function<bool(const S&)> holds, std::string reason) {
    conditions.push_back({std::move(holds), std::move(reason), false});
    return *this;
  }
  SettingField& needs(std::function<bool(const S&)> holds, std::string reason) {
    conditions.push_back({std::move(holds), std::move(reason), true});
    return *this;
  }
};

/// A setting as the reference page, the tests and Python's settings_reference() see it: its info,
/// its default at the edges and in SI, and its conditions in words.
struct SettingRow : SettingInfo {
  SettingValue default_value;  ///< in SI (as Python has it); monostate: unset
  std::string default_text;    ///< as the command line and configs take it ("0.83", "free")
  /// Its conditions in words: "needs ..." or "refused where it does nothing: ...".
  std::vector<std::string> conditions;
};

/// Which fields of a description an edge or a kind uses: `only` (if not empty) and not `exclude`;
/// `unchecked`: fields whose conditions it does not check (a kind that always took them so).
struct SettingsSelection {
  std::vector<std::string> only;
  std::vector<std::string> exclude;
  std::vector<std::string> unchecked = {};
  bool contains(const std::string& name) const;
  bool checks(const std::string& name) const;
};

// ---- values at the edges --------------------------------------------------------------------

/// A value as text: true/false, integers, numbers as {:g}, lists joined by ", ", unset as "".
std::string format_setting_value(const SettingValue& value);
/// The struct's value as the command line and configs take it (numbers in the edge unit, an
/// inverted switch negated).
SettingValue setting_edge_value(const SettingInfo& info, const SettingValue& value);
/// An edge's value as the struct takes it, checked first: finite, within min and max and the
/// member's limits, one of the choices (unless the setter checks them). `what` names the setting in
/// the errors ("--angle", "file.toml: coupon.grips").
SettingValue setting_struct_value(const SettingInfo& info, const SettingValue& edge_value,
                                  const std::string& what);
/// "{what} must be \"a\", \"b\" or \"c\", got \"x\"".
std::string choice_error(const std::string& what, const std::vector<std::string>& choices,
                         const std::string& value);
/// A reason's {name} and {name=value} placeholders as `edge` names the settings `find` knows (a
/// name it does not know stays as written).
std::string render_setting_reason(std::string_view reason, SettingEdge edge,
                                  const std::function<const SettingInfo*(std::string_view)>& find);
/// A help text with its unit: its {unit} placeholder replaced by `unit` ("[mm]"), or `unit`
/// appended where it has none; an empty `unit` removes the placeholder (the reference's own
/// column).
std::string help_with_unit(const std::string& help, const std::string& unit);
/// "--length-mm", "coupon.length_mm", "coupon.length" or the name, by edge.
std::string setting_edge_name(const SettingInfo& info, SettingEdge edge);

// ---- the description ------------------------------------------------------------------------

/// The fields of a settings struct S, and its defaults (the struct the commands start from).
template <class S>
class SettingsDescription {
 public:
  using Field = SettingField<S>;
  using Getter = std::function<SettingValue(const S&)>;
  using Setter = std::function<void(S&, const SettingValue&, const std::string&)>;

  explicit SettingsDescription(std::function<S()> defaults = [] { return S{}; })
      : defaults_(std::move(defaults)) {}

  S defaults() const { return defaults_(); }
  const std::deque<Field>& fields() const { return fields_; }
  /// The fields to change after they were added (edges a whole description lacks).
  std::deque<Field>& edit_fields() { return fields_; }
  const Field* find(std::string_view name) const {
    for (const Field& f : fields_)
      if (f.name == name) return &f;
    return nullptr;
  }
  const Field& at(std::string_view name) const {
    const Field* f = find(name);
    require(f != nullptr, "no setting '" + std::string(name) + "' is described");
    return *f;
  }
  /// The fields `selection` keeps, in declaration order.
  std::vector<const Field*> selected(const SettingsSelection& selection) const {
    std::vector<const Field*> out;
    for (const Field& f : fields_)
      if (selection.contains(f.name)) out.push_back(&f);
    return out;
  }

  /// A field with its accessors; the other add functions derive them from an accessor `access`
  /// (a generic lambda returning the member: [](auto& s) -> auto& { return s.coupon.length; }).
  Field& add(std::string name, SettingType type, Getter get, Setter set) {
    require(find(name) == nullptr, "setting '" + name + "' is described twice");
    Field& f = fields_.emplace_back();
    f.name = std::move(name);
    f.type = type;
    f.get = std::move(get);
    f.set = std::move(set);
    return f;
  }
  template <class Access>
  Field& number(std::string name, Access access) {
    return add(
        std::move(name), SettingType::kNumber,
        [access](const S& s) -> SettingValue { return static_cast<double>(access(s)); },
        [access](S& s, const SettingValue& v, const std::string&) {
          access(s) = std::get<double>(v);
        });
  }
  template <class Access>
  Field& integer(std::string name, Access access) {
    using Member = std::remove_cvref_t<decltype(access(std::declval<S&>()))>;
    Field& f = add(
        std::move(name), SettingType::kInteger,
        [access](const S& s) -> SettingValue { return static_cast<long>(access(s)); },
        [access](S& s, const SettingValue& v, const std::string&) {
          access(s) = static_cast<Member>(std::get<long>(v));
        });
    if constexpr (std::is_signed_v<Member>) {
      f.integer_min = static_cast<long>(std::numeric_limits<Member>::lowest());
    } else {
      f.integer_min = 0;
    }
    if constexpr (sizeof(Member) < sizeof(long)) {
      f.integer_max = static_cast<long>(std::numeric_limits<Member>::max());
    }
    return f;
  }
  template <class Access>
  Field& boolean(std::string name, Access access) {
    return add(
        std::move(name), SettingType::kSwitch,
        [access](const S& s) -> SettingValue { return static_cast<bool>(access(s)); },
        [access](S& s, const SettingValue& v, const std::string&) {
          access(s) = std::get<bool>(v);
        });
  }
  template <class Access>
  Field& text(std::string name, Access access) {
    using Member = std::remove_cvref_t<decltype(access(std::declval<S&>()))>;
    return add(
        std::move(name), SettingType::kText,
        [access](const S& s) -> SettingValue {
          if constexpr (std::is_same_v<Member, std::filesystem::path>) {
            return access(s).string();
          } else {
            return std::string(access(s));
          }
        },
        [access](S& s, const SettingValue& v, const std::string&) {
          access(s) = std::get<std::string>(v);
        });
  }

  /// The fields of `part` (a description of T, the member `access` returns), as fields of S: the
  /// same names and edges, Python's names under `python_prefix` ("coupon" -> "coupon.length").
  template <class T, class Access>
  void include(const SettingsDescription<T>& part, Access access,
               const std::string& python_prefix = "") {
    for (const SettingField<T>& p : part.fields()) {
      Field& f = add(
          p.name, p.type,
          [get = p.get, access](const S& s) -> SettingValue { return get(access(s)); },
          [set = p.set, access](S& s, const SettingValue& v, const std::string& what) {
            set(access(s), v, what);
          });
      static_cast<SettingInfo&>(f) = static_cast<const SettingInfo&>(p);
      if (!python_prefix.empty() && !f.python.empty()) f.python = python_prefix + "." + f.python;
      for (const auto& c : p.conditions) {
        f.conditions.push_back({[holds = c.holds, access](const S& s) { return holds(access(s)); },
                                c.reason, c.needs});
      }
    }
  }

  /// The names of the fields, for render_setting_reason.
  std::function<const SettingInfo*(std::string_view)> finder() const {
    return [this](std::string_view name) -> const SettingInfo* { return find(name); };
  }

  /// The first condition of a given field (by `given`) that `s` does not meet, as the error edge
  /// `edge` gives: "<what> does nothing here: <reason>" or "<what> needs <reason>"; throws it.
  void refuse_inapplicable(const S& s, const std::function<bool(const Field&)>& given,
                           SettingEdge edge,
                           const std::function<std::string(const Field&)>& what) const {
    for (const Field& f : fields_) {
      if (!given(f)) continue;
      for (const auto& c : f.conditions) {
        if (c.holds(s)) continue;
        const std::string reason = render_setting_reason(c.reason, edge, finder());
        throw Error(c.needs ? what(f) + " needs " + reason
                            : what(f) + " does nothing here: " + reason);
      }
    }
  }

  /// The fields `selection` keeps as rows, with the defaults of `defaults`.
  std::vector<SettingRow> rows(const S& defaults, const SettingsSelection& selection = {}) const {
    std::vector<SettingRow> out;
    for (const Field* f : selected(selection)) {
      SettingRow& row = out.emplace_back();
      static_cast<SettingInfo&>(row) = static_cast<const SettingInfo&>(*f);
      row.help =
          help_with_unit(render_setting_reason(f->help, SettingEdge::kReference, finder()), "");
      row.default_value = f->get(defaults);
      row.default_text = format_setting_value(setting_edge_value(*f, row.default_value));
      for (const auto& c : f->conditions) {
        const std::string reason =
            render_setting_reason(c.reason, SettingEdge::kReference, finder());
        row.conditions.push_back(c.needs ? "needs " + reason
                                         : "refused where it does nothing: " + reason);
      }
    }
    return out;
  }

 private:
  std::function<S()> defaults_;
  std::deque<Field> fields_;
};

}  // namespace plydem
