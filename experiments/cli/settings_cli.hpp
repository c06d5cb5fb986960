#pragma once
/// \file
/// The command line's edge of the settings descriptions (core/settings.hpp): CommandLineSettings
/// adds one CLI11 option for every field of a description that has a flag (its help with the
/// edge's unit, its default shown, its choices and range checked as CLI11 checks them) and, after
/// parsing, sets the given ones on a settings struct (numbers converted from their edge unit) and
/// refuses those that do nothing there ("--damping does nothing here: ...").

#include <CLI/CLI.hpp>

#include <deque>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "core/settings.hpp"

namespace plydem::cli {

/// A field's help as the command line shows it: other settings named by their flags, the edge's
/// unit, and `command`'s own note.
template <class S>
std::string command_line_help(const SettingsDescription<S>& d, const SettingField<S>& f,
                              const std::string& command) {
  std::string help =
      help_with_unit(render_setting_reason(f.help, SettingEdge::kCommandLine, d.finder()),
                     f.unit.edge.empty() ? "" : "[" + f.unit.edge + "]");
  if (f.optional) help += "; default: " + f.unset;
  for (const auto& [for_command, note] : f.command_notes)
    if (for_command == command) help += " (" + note + ")";
  return help;
}

template <class S>
class CommandLineSettings {
 public:
  /// Adds the options of the fields of `d` that `selection` keeps and that have a flag to `app`
  /// (the subcommand `command`, for the fields' command notes).
  CommandLineSettings(CLI::App& app, const SettingsDescription<S>& d, const std::string& command,
                      const SettingsSelection& selection = {})
      : d_(&d) {
    const S defaults = d.defaults();
    for (const SettingField<S>* f : d.selected(selection)) {
      if (f->flag.empty()) continue;
      Slot& slot = slots_.emplace_back();
      slot.field = f;
      const SettingValue value = f->get(defaults);
      set_slot(slot, setting_edge_value(*f, value));
      slot.option = add_option(app, slot, command_line_help(d, *f, command),
                               std::holds_alternative<std::monostate>(value));
    }
  }

  const SettingsDescription<S>& description() const { return *d_; }

  /// Sets the given options on `settings`, in the description's order; throws plydem::Error
  /// naming the flag for a value out of range or one the setter refuses.
  void apply(S& settings) const {
    for (const Slot& slot : slots_) {
      if (slot.option->count() == 0) continue;
      const SettingField<S>& f = *slot.field;
      f.set(settings, setting_struct_value(f, slot_value(slot), f.flag), f.flag);
    }
  }

  /// Throws "--x does nothing here: <reason>" (or "--x needs <reason>") for the first given
  /// option whose conditions `settings` does not meet.
  void refuse_inapplicable(const S& settings) const {
    d_->refuse_inapplicable(
        settings, [this](const SettingField<S>& f) { return given(f.name); },
        SettingEdge::kCommandLine, [](const SettingField<S>& f) { return f.flag; });
  }

  /// The defaults with the given options applied, refused where they do nothing.
  S settings() const {
    S s = d_->defaults();
    apply(s);
    refuse_inapplicable(s);
    return s;
  }

  /// Whether the option of the setting `name` was given.
  bool given(std::string_view name) const {
    const Slot* slot = find(name);
    return slot != nullptr && slot->option->count() > 0;
  }

  /// Whether any of the options was given, and the first one's flag.
  std::string first_given() const {
    for (const Slot& slot : slots_)
      if (slot.option->count() > 0) return slot.field->flag;
    return "";
  }

  /// A number as the command line has it (given, or its default) in the edge's unit: the angle
  /// in degrees as the user wrote it, for reports.
  double edge_number(std::string_view name) const {
    const Slot* slot = find(name);
    require(slot != nullptr && slot->field->type == SettingType::kNumber,
            "no number option '" + std::string(name) + "'");
    return slot->number;
  }

 private:
  struct Slot {
    const SettingField<S>* field = nullptr;
    CLI::Option* option = nullptr;
    bool on = false;
    long integer = 0;
    double number = 0;
    std::string text;
    std::vector<std::string> texts;
  };

  const Slot* find(std::string_view name) const {
    for (const Slot& slot : slots_)
      if (slot.field->name == name) return &slot;
    return nullptr;
  }

  static void set_slot(Slot& slot, const SettingValue& value) {
    if (const bool* b = std::get_if<bool>(&value)) slot.on = *b;
    if (const long* i = std::get_if<long>(&value)) slot.integer = *i;
    if (const double* x = std::get_if<double>(&value)) slot.number = *x;
    if (const std::string* s = std::get_if<std::string>(&value)) slot.text = *s;
    if (const auto* list = std::get_if<std::vector<std::string>>(&value)) slot.texts = *list;
  }

  static SettingValue slot_value(const Slot& slot) {
    switch (slot.field->type) {
      case SettingType::kSwitch:
        return slot.on;
      case SettingType::kInteger:
        return slot.integer;
      case SettingType::kNumber:
        return slot.number;
      case SettingType::kText:
        return slot.text;
      case SettingType::kTexts:
        return slot.texts;
    }
    return std::monostate{};
  }

  static CLI::Option* add_option(CLI::App& app, Slot& slot, const std::string& help, bool unset) {
    const SettingField<S>& f = *slot.field;
    CLI::Option* option = nullptr;
    switch (f.type) {
      case SettingType::kSwitch:
        return app.add_flag(f.flag, slot.on, help);
      case SettingType::kInteger:
        option = app.add_option(f.flag, slot.integer, help);
        break;
      case SettingType::kNumber:
        option = app.add_option(f.flag, slot.number, help);
        break;
      case SettingType::kText:
        option = app.add_option(f.flag, slot.text, help);
        break;
      case SettingType::kTexts:
        return app.add_option(f.flag, slot.texts, help);
    }
    if (f.choices && f.cli_checks_choices) option->check(CLI::IsMember(f.choices()));
    if (f.min && f.max && f.type == SettingType::kInteger) {
      option->check(CLI::Range(static_cast<long>(*f.min), static_cast<long>(*f.max)));
    } else if (f.min && f.max) {
      option->check(CLI::Range(*f.min, *f.max));
    } else if (f.min && *f.min == 0) {
      option->check(CLI::NonNegativeNumber);
    } else if (f.min) {
      option->check(CLI::Range(*f.min, std::numeric_limits<double>::max()));
    }
    if (f.show_default && !unset) option->capture_default_str();
    return option;
  }

  const SettingsDescription<S>* d_;
  std::deque<Slot> slots_;
};

}  // namespace plydem::cli
