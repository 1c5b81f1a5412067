// Readable tables on stdout and the same rows as JSON, plus the small statistics the scenarios share.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace rbbench {

struct Column {
  std::string header;
  std::string key;     // field of the row object
  int precision = -1;  // digits after the point for floating-point values; -1 = as stored
};

class Table {
 public:
  Table(std::string title, std::vector<Column> columns) : title_(std::move(title)), columns_(std::move(columns)) {}
  void add(const nlohmann::json& row) { rows_.push_back(row); }
  const nlohmann::json& rows() const { return rows_; }
  // Prints the title, a header line and one line per row, columns aligned.
  void print() const;

 private:
  std::string title_;
  std::vector<Column> columns_;
  nlohmann::json rows_ = nlohmann::json::array();
};

// Prints "  key: value" lines of a summary object (ratios and the like).
void printSummary(const nlohmann::json& summary);

double median(std::vector<double> values);
double minimum(const std::vector<double>& values);
// Median of values[1..] (the runs after the first); values[0] when there is only one.
double warmMedian(const std::vector<double>& values);
// a / b, or 0 when b is 0.
double ratio(double a, double b);
std::string humanCount(uint64_t n);  // 1000 -> "1k", 1000000 -> "1M", 300000 -> "300k"

}  // namespace rbbench
