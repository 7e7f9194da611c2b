// JSON files with errors that name the file and the field.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "io/png.hpp"

namespace pipeloc {

using Json = nlohmann::json;

Json read_json(const std::string& path);
void write_json(const std::string& path, const Json& value, int indent = 1);

// Fetches `key` of `obj` as T; throws IoError "<path>: <where>.<key>: expected <what>".
template <typename T>
T json_field(const Json& obj, const std::string& key, const std::string& path, const std::string& where,
             const char* what) {
  if (!obj.is_object() || !obj.contains(key))
    throw IoError("'" + path + "': " + where + ": missing '" + key + "' (" + what + ")");
  try {
    return obj.at(key).get<T>();
  } catch (const nlohmann::json::exception&) {
    throw IoError("'" + path + "': " + where + "." + key + ": expected " + what);
  }
}

}  // namespace pipeloc
