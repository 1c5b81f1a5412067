#include "report.h"

#include <algorithm>
#include <cstdio>

namespace rbbench {

namespace {

std::string cell(const nlohmann::json& v, int precision) {
  char buf[64];
  if (v.is_null()) return "-";
  if (v.is_string()) return v.get<std::string>();
  if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
  if (v.is_number_integer() || v.is_number_unsigned()) return v.dump();
  if (v.is_number_float()) {
    std::snprintf(buf, sizeof buf, "%.*f", precision < 0 ? 3 : precision, v.get<double>());
    return buf;
  }
  return v.dump();
}

}  // namespace

void Table::print() const {
  std::vector<size_t> width(columns_.size());
  std::vector<std::vector<std::string>> cells;
  for (size_t c = 0; c < columns_.size(); ++c) width[c] = columns_[c].header.size();
  for (const auto& row : rows_) {
    std::vector<std::string> line;
    for (size_t c = 0; c < columns_.size(); ++c) {
      line.push_back(
          cell(row.contains(columns_[c].key) ? row[columns_[c].key] : nlohmann::json(), columns_[c].precision));
      width[c] = std::max(width[c], line.back().size());
    }
    cells.push_back(std::move(line));
  }
  std::printf("\n== %s\n", title_.c_str());
  for (size_t c = 0; c < columns_.size(); ++c)
    std::printf("%s%*s", c ? "  " : "", int(width[c]), columns_[c].header.c_str());
  std::printf("\n");
  for (const auto& line : cells) {
    for (size_t c = 0; c < line.size(); ++c) std::printf("%s%*s", c ? "  " : "", int(width[c]), line[c].c_str());
    std::printf("\n");
  }
  std::fflush(stdout);
}

void printSummary(const nlohmann::json& summary) {
  for (auto it = summary.begin(); it != summary.end(); ++it) {
    std::printf("  %s: %s\n", it.key().c_str(), cell(it.value(), 3).c_str());
  }
  std::fflush(stdout);
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double minimum(const std::vector<double>& v) { return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end()); }

double warmMedian(const std::vector<double>& v) {
  if (v.size() <= 1) return v.empty() ? 0.0 : v[0];
  return median(std::vector<double>(v.begin() + 1, v.end()));
}

double ratio(double a, double b) { return b != 0.0 ? a / b : 0.0; }

std::string humanCount(uint64_t n) {
  if (n >= 1000000 && n % 1000000 == 0) return std::to_string(n / 1000000) + "M";
  if (n >= 1000 && n % 1000 == 0) return std::to_string(n / 1000) + "k";
  return std::to_string(n);
}

}  // namespace rbbench
