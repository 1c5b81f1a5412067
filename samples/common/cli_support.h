// Command lines of the samples' executables, on top of CLI11: validators whose errors name the bad value and
// the valid range or names (CLI11 prefixes the option: "--width: 0 is outside 1..16384"), value parsers for
// lists, sizes and name sets, and one parse call that turns CLI11's exceptions into a message. Knows neither
// Vulkan nor Raybridge, so the sample engine's demo uses it too.
//
//   CLI::App app{"what the tool does", "tool-name"};
//   rbCli::prepare(app);                                  // before adding options: repeated options keep the last
//   app.add_option("--width", o.width, "image width")->check(rbCli::wholeNumber(1, 16384));
//   rbCli::addEnum(app, "--mode", o.mode, {{"raster", Mode::Raster}, {"hybrid", Mode::Hybrid}}, "...");
//   bool help = false;
//   if (std::string e = rbCli::parse(app, argc, argv, help); !e.empty()) ...   // help: print app.help()
//
// Thread safety: plain functions; a CLI::App is used from one thread.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

namespace rbCli {

// 'text', for values in messages.
std::string quote(std::string_view text);
// "a|b|c" for separator "|".
std::string join(const std::vector<std::string>& names, std::string_view separator);
// "a", "a or b", "a, b or c" (lastSeparator " or "; ", " gives a plain list).
std::string joinNames(const std::vector<std::string>& names, std::string_view lastSeparator = " or ");

// Whole number in min..max: "'abc' is not a whole number in 1..64", "0 is outside 1..64", "'010' has a leading
// zero; give 10 (1..64)" (CLI11's conversion would read it as octal). The description (shown in --help after the
// type name) is "min..max".
CLI::Validator wholeNumber(uint64_t min, uint64_t max);
// Returns "" and sets `out`, or the error above.
std::string parseWholeNumber(std::string_view text, uint64_t min, uint64_t max, uint64_t& out);
// 0 or a whole number in min..max: "5 is outside 1024..8192 (or 0 = <zeroMeaning>)".
CLI::Validator zeroOrWholeNumber(uint64_t min, uint64_t max, const std::string& zeroMeaning);

// A bound of a real-number range; a default Bound leaves that side open.
struct Bound {
  double value = 0.0;
  bool inclusive = false;
  bool bounded = false;  // false = no bound on this side
};
inline Bound atLeast(double v) { return {v, true, true}; }
inline Bound above(double v) { return {v, false, true}; }
inline Bound atMost(double v) { return {v, true, true}; }
inline Bound below(double v) { return {v, false, true}; }
inline Bound unbounded() { return {}; }
// A finite real number within the bounds: "'abc' is not a number", "'inf' is not finite; give a finite
// number", "-1 must be greater than 0", "-1 is negative; give 0 or more", "1.5 is outside (0, 1]". `unit`, if
// given, follows the range ("is outside [0, 45) degrees", "must be greater than 0 (world units)").
CLI::Validator realNumber(Bound low, Bound high = unbounded(), const std::string& unit = "");
// Returns "" and sets `out`, or the error above.
std::string parseReal(std::string_view text, Bound low, Bound high, const std::string& unit, double& out);
// As realNumber, for an option stored in a float: the value as a 32-bit float must be finite and within the bounds
// ("'1e39' is too large for a 32-bit float (magnitude above 3.40282e+38)", "1e-50 is 0 as a 32-bit float, which
// must be greater than 0").
CLI::Validator floatNumber(Bound low, Bound high = unbounded(), const std::string& unit = "");
// Returns "" and sets `out`, or the error above.
std::string parseFloatReal(std::string_view text, Bound low, Bound high, const std::string& unit, float& out);

// A value that is not empty: "the <what> is empty" (e.g. what = "file name").
CLI::Validator nonEmpty(const std::string& what);

// A name from `names`: "'cosine' is not binary or distance".
CLI::Validator oneOf(std::vector<std::string> names);

// "x,y,z,...": exactly `count` numbers, finite as 32-bit floats. Errors: "'x' in '1,x,0' is not a number", "'nan' in
// 'nan,0,0' is not finite; give a finite number", "'1e39' in '1e39,0,0' is too large for a 32-bit float (magnitude
// above 3.40282e+38)", "expected 3 comma-separated numbers, got 2 in '1,2'".
std::string parseNumberList(std::string_view text, size_t count, std::vector<float>& out);
CLI::Validator numberList(size_t count);
// "1,10,50": one or more whole numbers in min..max.
std::string parseWholeNumberList(std::string_view text, uint64_t min, uint64_t max, std::vector<uint32_t>& out);
// "WxH" with both in min..max: "'640' is not WxH (e.g. 1280x720)", "width 0 in '0x720' is outside 1..16384".
std::string parseSize(std::string_view text, uint32_t min, uint32_t max, uint32_t& width, uint32_t& height);
// A comma-separated subset of `names` ("" = none): `out` gets bit i for names[i]. Error: "'bogus' in 'a,bogus'
// is not <what> (a, b, c)", e.g. what = "an effect".
std::string parseNameSet(std::string_view text, const std::vector<std::string>& names, std::string_view what,
                         uint32_t& out);

// Prepares an App for the conventions of our tools: a repeated option keeps its last value (as the shell
// scripts expect), option names are matched exactly. Call before adding options.
void prepare(CLI::App& app);

// --NAME taking one of the names in `table`, stored in `target` (which must outlive the parse). The help shows
// the names as the type ("binary|distance").
template <class T>
CLI::Option* addEnum(CLI::App& app, const std::string& name, T& target, std::vector<std::pair<std::string, T>> table,
                     const std::string& description) {
  std::vector<std::string> names;
  for (const auto& entry : table) names.push_back(entry.first);
  const std::string type = join(names, "|");
  return app
      .add_option_function<std::string>(
          name,
          [&target, table](const std::string& value) {
            for (const auto& [n, v] : table)
              if (n == value) target = v;
          },
          description)
      ->check(oneOf(std::move(names)))
      ->type_name(type);
}

// Parses argv. Returns "" on success; `help` is set when -h/--help was given (print app.help() and exit 0).
// Otherwise the error, naming the option and the value: the validators' messages above, "unknown option
// '--x'", "unexpected argument 'x'", or CLI11's own ("--width: 1 required N missing").
std::string parse(CLI::App& app, int argc, const char* const* argv, bool& help);

// argv joined by spaces, for reports.
std::string commandLine(int argc, const char* const* argv);

}  // namespace rbCli
