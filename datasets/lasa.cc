#include "datasets/lasa.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "core/parse.h"

namespace foresight {
namespace {

namespace fs = std::filesystem;

constexpr const char* kHeader = "demo,t,x,y,vx,vy,ax,ay";
constexpr std::array<const char*, 8> kColumns = {"demo", "t", "x", "y", "vx", "vy", "ax", "ay"};

/// Rows of one demonstration, column by column (t, x, y, vx, vy).
struct DemoRows {
  std::vector<double> t, x, y, vx, vy;
};

Demonstration ToDemonstration(const DemoRows& rows) {
  const auto n = static_cast<Eigen::Index>(rows.t.size());
  Demonstration d;
  d.time = Eigen::Map<const Eigen::VectorXd>(rows.t.data(), n);
  d.position.resize(2, n);
  d.velocity.resize(2, n);
  d.position.row(0) = Eigen::Map<const Eigen::RowVectorXd>(rows.x.data(), n);
  d.position.row(1) = Eigen::Map<const Eigen::RowVectorXd>(rows.y.data(), n);
  d.velocity.row(0) = Eigen::Map<const Eigen::RowVectorXd>(rows.vx.data(), n);
  d.velocity.row(1) = Eigen::Map<const Eigen::RowVectorXd>(rows.vy.data(), n);
  return d;
}

}  // namespace

std::vector<std::string> ListLasaShapes(const std::string& lasa_dir) {
  const fs::path csv = fs::path(lasa_dir) / "csv";
  std::error_code ec;
  FS_THROW_UNLESS(fs::is_directory(csv, ec), "ListLasaShapes: ", csv.string(),
                  " is not a directory (expected the LASA CSV export, see "
                  "lasa_handwriting/README.md)");
  std::vector<std::string> shapes;
  for (const fs::directory_entry& entry : fs::directory_iterator(csv, ec))
    if (entry.is_regular_file() && entry.path().extension() == ".csv")
      shapes.push_back(entry.path().stem().string());
  FS_THROW_UNLESS(!ec, "ListLasaShapes: cannot list ", csv.string(), ": ", ec.message());
  FS_THROW_UNLESS(!shapes.empty(), "ListLasaShapes: no .csv file in ", csv.string());
  std::sort(shapes.begin(), shapes.end());
  return shapes;
}

DemoSet ReadLasaShape(const std::string& lasa_dir, const std::string& shape) {
  const std::string path = (fs::path(lasa_dir) / "csv" / (shape + ".csv")).string();
  std::ifstream in(path);
  FS_THROW_UNLESS(in.good(), path, ": cannot open LASA shape '", shape, "'");

  std::string text;
  std::size_t line = 1;
  FS_THROW_UNLESS(static_cast<bool>(std::getline(in, text)), path, ":1: empty file");
  if (!text.empty() && text.back() == '\r') text.pop_back();
  FS_THROW_UNLESS(text == kHeader, path, ":1: header is '", text, "', expected '", kHeader, "'");

  std::vector<DemoRows> demos;
  std::array<double, 8> v{};
  std::string field;
  while (std::getline(in, text)) {
    ++line;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    if (text.empty()) continue;
    std::size_t count = 0, begin = 0;
    while (true) {
      const std::size_t end = std::min(text.find(',', begin), text.size());
      field.assign(text, begin, end - begin);
      FS_THROW_UNLESS(count < v.size(), path, ":", line, ": more than ", v.size(),
                      " fields (expected ", kHeader, ")");
      const std::optional<double> parsed = ParseDouble(field);
      FS_THROW_UNLESS(parsed.has_value(), path, ":", line, ": column '", kColumns[count],
                      "' is not a number: '", field, "'");
      FS_THROW_UNLESS(std::isfinite(*parsed), path, ":", line, ": column '", kColumns[count],
                      "' is not finite: '", field, "'");
      v[count++] = *parsed;
      if (end == text.size()) break;
      begin = end + 1;
    }
    FS_THROW_UNLESS(count == v.size(), path, ":", line, ": ", count, " fields, expected ", v.size(),
                    " (", kHeader, ")");
    // At most 2^53: larger doubles do not hold every integer and overflow the size_t conversion.
    FS_THROW_UNLESS(v[0] == std::floor(v[0]) && v[0] >= 0 && v[0] <= 9007199254740992.0, path, ":",
                    line, ": demo index is not a non-negative integer (at most 2^53): ", v[0]);
    const auto demo = static_cast<std::size_t>(v[0]);
    const std::size_t current = demos.empty() ? 0 : demos.size() - 1;
    FS_THROW_UNLESS(demo == demos.size() || (!demos.empty() && demo == current), path, ":", line,
                    ": demo index ", demo, " out of order (",
                    demos.empty() ? std::string("the first row must be demo 0")
                                  : internal::Concat("after demo ", current, ", expected ", current,
                                                     " or ", current + 1),
                    ")");
    if (demo == demos.size()) demos.emplace_back();
    DemoRows& rows = demos.back();
    FS_THROW_UNLESS(rows.t.empty() || v[1] > rows.t.back(), path, ":", line, ": time ", v[1],
                    " does not increase within demo ", demo, " (previous ",
                    rows.t.empty() ? 0.0 : rows.t.back(), ")");
    rows.t.push_back(v[1]);
    rows.x.push_back(v[2]);
    rows.y.push_back(v[3]);
    rows.vx.push_back(v[4]);
    rows.vy.push_back(v[5]);
  }
  FS_THROW_UNLESS(!in.bad(), path, ": read error after line ", line);
  FS_THROW_UNLESS(!demos.empty(), path, ": no data rows after the header");

  DemoSet set;
  set.name = shape;
  set.dimension = 2;
  for (const DemoRows& rows : demos) set.demos.push_back(ToDemonstration(rows));
  return set;
}

}  // namespace foresight
