#include "io/results_csv.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include "io/png.hpp"

namespace pipeloc {
namespace {

bool parse_numbers(const std::string& field, std::size_t n, std::vector<double>* out) {
  std::istringstream in(field);
  out->clear();
  double v;
  while (in >> v) {
    if (!std::isfinite(v)) return false;
    out->push_back(v);
  }
  return in.eof() && out->size() == n;
}

bool parse_int(const std::string& s, int* out) {
  try {
    std::size_t used = 0;
    *out = std::stoi(s, &used);
    return used == s.size();
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace

ResultsFile read_results_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError("results CSV '" + path + "': cannot open file");
  ResultsFile file;
  std::string line;
  int line_no = 0;
  auto reject = [&](const std::string& why) {
    ++file.malformed;
    if (file.first_errors.size() < 5)
      file.first_errors.push_back("line " + std::to_string(line_no) + ": " + why);
  };
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line.rfind("scene_id", 0) == 0) continue;
    std::vector<std::string> fields;
    std::stringstream ss(line);
    std::string f;
    while (std::getline(ss, f, ',')) fields.push_back(f);
    if (fields.size() != 7) {
      reject("expected 7 comma-separated fields, got " + std::to_string(fields.size()));
      continue;
    }
    ResultRow row;
    std::vector<double> r, t, one;
    if (!parse_int(fields[0], &row.scene_id) || !parse_int(fields[1], &row.im_id) ||
        !parse_int(fields[2], &row.obj_id)) {
      reject("scene_id, im_id and obj_id must be integers");
      continue;
    }
    if (!parse_numbers(fields[3], 1, &one)) {
      reject("score must be a number");
      continue;
    }
    row.score = one[0];
    if (!parse_numbers(fields[4], 9, &r) || !parse_numbers(fields[5], 3, &t)) {
      reject("R must be 9 and t 3 space-separated numbers");
      continue;
    }
    Eigen::Matrix3d m;
    m << r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8];
    if (std::abs(m.determinant() - 1.0) > 1e-2 ||
        (m.transpose() * m - Eigen::Matrix3d::Identity()).norm() > 1e-2) {
      reject("R is not a rotation");
      continue;
    }
    row.model_to_cam =
        pose_from_rt({r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8]}, {t[0], t[1], t[2]});
    row.time_s = parse_numbers(fields[6], 1, &one) ? one[0] : -1;
    file.rows.push_back(row);
  }
  return file;
}

void write_results_header(std::ostream& out) { out << "scene_id,im_id,obj_id,score,R,t,time\n"; }

void write_result_row(std::ostream& out, const ResultRow& row) {
  const auto r = rotation_rowmajor(row.model_to_cam);
  const auto t = translation_mm(row.model_to_cam);
  std::ostringstream s;
  s.precision(9);
  s << row.scene_id << ',' << row.im_id << ',' << row.obj_id << ',' << row.score << ',';
  for (int i = 0; i < 9; ++i) s << (i ? " " : "") << r[i];
  s << ',' << t[0] << ' ' << t[1] << ' ' << t[2] << ',' << row.time_s << '\n';
  out << s.str();
}

}  // namespace pipeloc
