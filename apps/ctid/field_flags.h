// Flags generated from fields() lists (core/fields.h, decision 0046): one CLI11 option per field
// of an options struct, spelt "--" + flag_spelling(field), its help the field's doc, its value
// stored straight into the struct. The value rules are not restated here: the struct's
// validate() checks them, and run_command names the flag in its message (with_flag_names reads
// the paths recorded here). Fields a command reads in another form (a model file, MIN:MAX) are
// listed in `by_hand` and registered by the command under the same spelling (flag_of).
#pragma once

#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "ctid/core/fields.h"
#include "ctid/core/hold.h"

namespace ctid::cli {

struct FieldFlagSettings {
  /// Help group of the generated flags ("" leaves CLI11's default).
  std::string group;
  /// Paths of fields ("refined_iv.initial_model") whose flag the command adds itself.
  std::vector<std::string> by_hand;
  /// Paths of fields the command line cannot give (a matrix): no flag, by choice.
  std::vector<std::string> none;
  /// A flag each generated one needs ("--two-stage"), or "".
  std::string needs;
  /// The object's path in validation messages ("IdentificationOptions.two_stage");
  /// "" gives S::type_name.
  std::string path;
};

/// Records that the flag `flag` of `app` sets the field at `path` (a validation message's
/// "IdentificationOptions.refined_iv.output_interpolation"), for with_flag_names.
void record_field_flag(const CLI::App& app, const std::string& path, const std::string& flag);
/// The flag recorded for the longest leading part of `components` below `type` (joined by
/// '.'), with what remains of the path in parentheses ("--delay-scan (max)"); "" when none.
std::string recorded_field_flag(const CLI::App& app, const std::string& type,
                                const std::vector<std::string>& components);

/// An enumeration whose words on the command line are not its enumerators' names specialises
/// this with `static std::vector<std::pair<std::string, E>> words()` (the holds: zoh and foh,
/// as every command has spelt them).
template <class E>
struct CommandLineWords;
template <>
struct CommandLineWords<Hold> {
  static std::vector<std::pair<std::string, Hold>> words() {
    return {{"zoh", Hold::zero_order_hold}, {"foh", Hold::first_order_hold}};
  }
};

/// The words an enumeration takes on the command line with their values: its enumerators'
/// names unless CommandLineWords says otherwise.
template <NamedEnum E>
std::vector<std::pair<std::string, E>> command_line_names() {
  if constexpr (requires { CommandLineWords<E>::words(); }) {
    return CommandLineWords<E>::words();
  } else {
    std::vector<std::pair<std::string, E>> names;
    for (const auto& e : enumerators(E{})) names.emplace_back(std::string(e.name), e.value);
    return names;
  }
}

/// "a, b or c": command_line_names for help and messages.
template <NamedEnum E>
std::string command_line_list() {
  const auto names = command_line_names<E>();
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) out += i + 1 == names.size() ? " or " : ", ";
    out += names[i].first;
  }
  return out;
}

/// The value of E called `word` on the command line; throws CLI::ValidationError naming the
/// flag, the word and the names it may be otherwise ("--method is 'pp'; it must be ...").
template <NamedEnum E>
E parse_enum_word(const std::string& flag, const std::string& word) {
  for (const auto& [name, value] : command_line_names<E>()) {
    if (name == word) return value;
  }
  throw CLI::ValidationError(flag + " is '" + word + "'; it must be " + command_line_list<E>());
}

template <NamedEnum E>
std::string command_line_word(E value) {
  for (const auto& [name, each] : command_line_names<E>()) {
    if (each == value) return name;
  }
  return "?";
}

/// "--max-iterations": the flag of S's field at `path` ("refined_iv.max_iterations").
template <HasFields S>
std::string flag_of(const std::string& path) {
  for (const FieldFlag& f : field_flags<S>()) {
    if (f.path == path) return "--" + f.flag;
  }
  throw std::logic_error(std::string(S::type_name) + " has no field " + path);
}

namespace field_flags_internal {

template <class T>
inline constexpr bool is_number = std::is_arithmetic_v<T> && !std::is_same_v<T, bool>;

std::string help_text(std::string_view doc);

// One option for one field of a type the command line spells as a word or a list; nullptr
// for a type it does not.
template <class T>
CLI::Option* add_value(CLI::App& app, const std::string& flag, T& value, const std::string& doc) {
  if constexpr (std::is_same_v<T, bool>) {
    // A default-true flag is turned off by --no-NAME as well as by --NAME=false.
    if (value) return app.add_flag(flag + ",!--no-" + flag.substr(2), value, doc);
    return app.add_flag(flag, value, doc);
  } else if constexpr (is_number<T> || std::is_same_v<T, std::string>) {
    return app.add_option(flag, value, doc)->capture_default_str();
  } else if constexpr (NamedEnum<T>) {
    return app
        .add_option_function<std::string>(
            flag,
            [flag, &value](const std::string& word) { value = parse_enum_word<T>(flag, word); },
            doc + " (" + command_line_list<T>() + ")")
        ->type_name("WORD")
        ->default_str(command_line_word(value));
  } else if constexpr (is_optional<T>::value) {
    using Inner = typename T::value_type;
    if constexpr (is_number<Inner>) {
      return app.add_option_function<Inner>(
          flag, [&value](const Inner& number) { value = number; }, doc + " (default: none)");
    } else if constexpr (NamedEnum<Inner>) {
      return app
          .add_option_function<std::string>(
              flag,
              [flag, &value](const std::string& word) {
                value = parse_enum_word<Inner>(flag, word);
              },
              doc + " (" + command_line_list<Inner>() + "; default: none)")
          ->type_name("WORD");
    } else if constexpr (requires(std::string_view w) { Inner::from_flag(w); }) {
      // A struct spelt as one word (its flag_form), read by its own from_flag.
      return app
          .add_option_function<std::string>(
              flag,
              [flag, &value](const std::string& word) {
                try {
                  value = Inner::from_flag(word);
                } catch (const std::invalid_argument& e) {
                  throw CLI::ValidationError(flag + ": " + e.what());
                }
              },
              doc + " (default: none)")
          ->type_name(std::string(Inner::flag_form));
    } else {
      return nullptr;
    }
  } else if constexpr (is_vector<T>::value && is_number<typename T::value_type>) {
    return app.add_option(flag, value, doc + " (comma-separated)")
        ->delimiter(',')
        ->capture_default_str();
  } else {
    return nullptr;
  }
}

template <HasFields S>
void add_flags(CLI::App& app, S& object, const FieldFlagSettings& settings,
               const std::string& relative, const std::string& flag_prefix) {
  for_each_field<S>([&](const auto& f) {
    using T = typename std::decay_t<decltype(f)>::value_type;
    const std::string path = relative + std::string(f.name);
    const std::string recorded = settings.path + "." + path;
    const std::string flag = "--" + flag_prefix + flag_spelling(f);
    bool by_hand = false;
    for (const std::string& p : settings.by_hand) by_hand = by_hand || p == path;
    for (const std::string& p : settings.none) {
      if (p == path) return;
    }
    if constexpr (HasFieldFlags<T>) {
      if (by_hand) return;
      const std::string prefix = f.flag_given && !f.flag.empty() ? flag_spelling(f) + "-" : "";
      add_flags(app, object.*(f.member), settings, path + ".", flag_prefix + prefix);
    } else {
      record_field_flag(app, recorded, flag);
      if (by_hand) return;
      CLI::Option* option = add_value(app, flag, object.*(f.member), help_text(f.doc));
      if (option == nullptr) {
        throw std::logic_error(recorded + " has no command-line form; list it in by_hand");
      }
      if (!settings.group.empty()) option->group(settings.group);
      if (!settings.needs.empty()) option->needs(settings.needs);
    }
  });
}

}  // namespace field_flags_internal

/// Adds one flag of `app` per field of `object` (nested structs' fields in place, under the
/// prefix their field carries), each storing into `object`, which must outlive the parse.
template <HasFields S>
void add_field_flags(CLI::App& app, S& object, FieldFlagSettings settings = {}) {
  if (settings.path.empty()) settings.path = std::string(S::type_name);
  field_flags_internal::add_flags(app, object, settings, "", "");
}

}  // namespace ctid::cli
