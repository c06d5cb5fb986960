#include "core/toml_reader.hpp"

#include "core/error.hpp"

namespace plydem {

namespace {

Error syntax_error(const toml::parse_error& e, const TomlErrorMessage& message) {
  const toml::source_position& where = e.source().begin;
  return Error(message(TomlSyntaxError{where.line, where.column, e.description()}));
}

}  // namespace

toml::table parse_toml(std::string_view text, std::string_view origin,
                       const TomlErrorMessage& message) {
  try {
    return toml::parse(text, origin);
  } catch (const toml::parse_error& e) {
    throw syntax_error(e, message);
  }
}

toml::table parse_toml_file(const std::string& path, const TomlErrorMessage& message) {
  try {
    return toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    throw syntax_error(e, message);
  }
}

std::optional<double> toml_number(const toml::node& node) {
  if (const auto* value = node.as_floating_point()) return value->get();
  if (const auto* value = node.as_integer()) return static_cast<double>(value->get());
  return std::nullopt;
}

}  // namespace plydem
