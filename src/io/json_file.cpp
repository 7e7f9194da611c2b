#include "io/json_file.hpp"

#include <fstream>

namespace pipeloc {

Json read_json(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError("'" + path + "': cannot open file");
  try {
    return Json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw IoError("'" + path + "': not valid JSON (byte " + std::to_string(e.byte) + ")");
  }
}

void write_json(const std::string& path, const Json& value, int indent) {
  std::ofstream out(path);
  if (!out) throw IoError("'" + path + "': cannot open for writing");
  out << value.dump(indent) << '\n';
  if (!out) throw IoError("'" + path + "': write failed");
}

}  // namespace pipeloc
