// A validator for the subset of JSON Schema (2020-12) that schema/report.schema.json uses, for the tests.
// Keywords: type (a name or a list), properties, required, additionalProperties (bool or schema), items,
// minItems, maxItems, minimum, maximum, exclusiveMinimum, exclusiveMaximum, enum, const, pattern, and $ref to
// "#/$defs/NAME". Annotations ($schema, $id, title, description, $defs) are skipped; any other keyword is
// reported as an error, so a schema cannot rely on a keyword this validator would silently ignore.
#pragma once

#include <regex>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace polysquare::test {

/// One message per violation, each starting with the JSON pointer of the offending value ("" = root).
inline void validate_json(const nlohmann::json& schema, const nlohmann::json& value, const nlohmann::json& root,
                          const std::string& at, std::vector<std::string>& errors) {
  if (schema.is_boolean()) {
    if (!schema.get<bool>()) errors.push_back(at + ": not allowed");
    return;
  }
  auto fail = [&](const std::string& what) { errors.push_back(at + ": " + what); };
  auto is_type = [&](const std::string& t) {
    if (t == "object") return value.is_object();
    if (t == "array") return value.is_array();
    if (t == "string") return value.is_string();
    if (t == "boolean") return value.is_boolean();
    if (t == "null") return value.is_null();
    if (t == "number") return value.is_number();
    if (t == "integer") return value.is_number_integer() ||
                               (value.is_number_float() && value.get<double>() == static_cast<double>(static_cast<long long>(value.get<double>())));
    errors.push_back(at + ": unknown type name " + t);
    return false;
  };
  for (const auto& [key, arg] : schema.items()) {
    if (key == "$schema" || key == "$id" || key == "title" || key == "description" || key == "$defs") continue;
    if (key == "$ref") {
      const std::string ref = arg.get<std::string>();
      const std::string prefix = "#/$defs/";
      if (ref.rfind(prefix, 0) != 0 || !root.contains("$defs") || !root["$defs"].contains(ref.substr(prefix.size()))) {
        fail("unresolvable $ref " + ref);
        continue;
      }
      validate_json(root["$defs"][ref.substr(prefix.size())], value, root, at, errors);
    } else if (key == "type") {
      bool ok = false;
      if (arg.is_array()) {
        for (const auto& t : arg) ok = ok || is_type(t.get<std::string>());
      } else {
        ok = is_type(arg.get<std::string>());
      }
      if (!ok) fail("is " + std::string(value.type_name()) + ", not " + arg.dump());
    } else if (key == "properties") {
      if (!value.is_object()) continue;
      for (const auto& [name, sub] : arg.items())
        if (value.contains(name)) validate_json(sub, value[name], root, at + "/" + name, errors);
    } else if (key == "additionalProperties") {
      if (!value.is_object()) continue;
      for (const auto& [name, v] : value.items())
        if (!schema.contains("properties") || !schema["properties"].contains(name))
          validate_json(arg, v, root, at + "/" + name, errors);
    } else if (key == "required") {
      if (!value.is_object()) continue;
      for (const auto& name : arg)
        if (!value.contains(name.get<std::string>())) fail("lacks \"" + name.get<std::string>() + "\"");
    } else if (key == "items") {
      if (!value.is_array()) continue;
      for (std::size_t i = 0; i < value.size(); ++i) validate_json(arg, value[i], root, at + "/" + std::to_string(i), errors);
    } else if (key == "minItems" || key == "maxItems") {
      if (!value.is_array()) continue;
      const auto n = arg.get<std::size_t>();
      if (key == "minItems" ? value.size() < n : value.size() > n)
        fail(std::to_string(value.size()) + " items, " + key + " " + std::to_string(n));
    } else if (key == "minimum" || key == "maximum" || key == "exclusiveMinimum" || key == "exclusiveMaximum") {
      if (!value.is_number()) continue;
      const double v = value.get<double>(), b = arg.get<double>();
      const bool ok = key == "minimum" ? v >= b : key == "maximum" ? v <= b : key == "exclusiveMinimum" ? v > b : v < b;
      if (!ok) fail(value.dump() + " breaks " + key + " " + arg.dump());
    } else if (key == "enum") {
      bool found = false;
      for (const auto& e : arg) found = found || e == value;
      if (!found) fail(value.dump() + " is not one of " + arg.dump());
    } else if (key == "const") {
      if (!(arg == value)) fail(value.dump() + " is not " + arg.dump());
    } else if (key == "pattern") {
      if (value.is_string() && !std::regex_search(value.get<std::string>(), std::regex(arg.get<std::string>())))
        fail(value.dump() + " does not match " + arg.dump());
    } else {
      fail("unsupported schema keyword " + key);
    }
  }
}

inline std::vector<std::string> validate_json(const nlohmann::json& schema, const nlohmann::json& value) {
  std::vector<std::string> errors;
  validate_json(schema, value, schema, "", errors);
  return errors;
}

}  // namespace polysquare::test
