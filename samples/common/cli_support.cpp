// Command-line helpers on top of CLI11 (see the header).
#include "cli_support.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace rbCli {

namespace {

std::string range(uint64_t min, uint64_t max) { return std::to_string(min) + ".." + std::to_string(max); }

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// Every digit of v: parsing it gives v back.
std::string number17(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// Digits only; values too large for uint64_t come back as UINT64_MAX (outside any range we use).
bool parseWhole(std::string_view text, uint64_t& out) {
  if (text.empty() || text.find_first_not_of("0123456789") != std::string_view::npos) return false;
  if (text.size() > 19) {
    out = UINT64_MAX;
    return true;
  }
  out = std::strtoull(std::string(text).c_str(), nullptr, 10);
  return true;
}

// CLI11 converts an option's value after the validators accepted it, reading "0640" as octal (416) and failing
// on "09": a leading zero is refused here, naming the number meant.
std::string leadingZeroError(std::string_view text, uint64_t value, const std::string& valid) {
  if (text.size() < 2 || text[0] != '0') return {};
  return quote(text) + " has a leading zero; give " + std::to_string(value) + " (" + valid + ")";
}

std::string wholeError(std::string_view text, uint64_t min, uint64_t max, uint64_t& out) {
  if (!parseWhole(text, out)) return quote(text) + " is not a whole number in " + range(min, max);
  if (out < min || out > max) return std::string(text) + " is outside " + range(min, max);
  return leadingZeroError(text, out, range(min, max));
}

constexpr double kFloatMax = 3.4028234663852886e38;  // FLT_MAX

// An item of a number list: "" or the error's predicate ("is not a number", "is not finite; ...").
std::string floatItemError(std::string_view text, float& out) {
  double d = 0.0;
  if (std::string e = parseReal(text, {}, {}, "", d); !e.empty()) return e.substr(quote(text).size());
  out = float(d);
  if (!std::isfinite(out)) return " is too large for a 32-bit float (magnitude above " + number(kFloatMax) + ")";
  return {};
}

}  // namespace

std::string quote(std::string_view text) { return "'" + std::string(text) + "'"; }

std::string join(const std::vector<std::string>& names, std::string_view separator) {
  std::string s;
  for (size_t i = 0; i < names.size(); ++i) (i ? s.append(separator) : s).append(names[i]);
  return s;
}

std::string joinNames(const std::vector<std::string>& names, std::string_view lastSeparator) {
  std::string s;
  for (size_t i = 0; i < names.size(); ++i) {
    if (i) s += i + 1 == names.size() ? std::string(lastSeparator) : std::string(", ");
    s += names[i];
  }
  return s;
}

std::string parseWholeNumber(std::string_view text, uint64_t min, uint64_t max, uint64_t& out) {
  return wholeError(text, min, max, out);
}

CLI::Validator wholeNumber(uint64_t min, uint64_t max) {
  return CLI::Validator(
      [min, max](std::string& value) {
        uint64_t v = 0;
        return wholeError(value, min, max, v);
      },
      range(min, max));
}

CLI::Validator zeroOrWholeNumber(uint64_t min, uint64_t max, const std::string& zeroMeaning) {
  return CLI::Validator(
      [min, max, zeroMeaning](std::string& value) -> std::string {
        uint64_t v = 0;
        if (!parseWhole(value, v))
          return quote(value) + " is not a whole number in " + range(min, max) + " (or 0 = " + zeroMeaning + ")";
        if (v != 0 && (v < min || v > max))
          return value + " is outside " + range(min, max) + " (or 0 = " + zeroMeaning + ")";
        return leadingZeroError(value, v, range(min, max) + ", or 0 = " + zeroMeaning);
      },
      "0|" + range(min, max));
}

std::string parseReal(std::string_view text, Bound low, Bound high, const std::string& suffix, double& out) {
  const std::string s(text);
  char* end = nullptr;
  const double v = s.empty() || std::isspace(static_cast<unsigned char>(s[0])) ? 0.0 : std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size()) return quote(text) + " is not a number";
  if (!std::isfinite(v)) return quote(text) + " is not finite; give a finite number";
  const bool lowOk = !low.bounded || (low.inclusive ? v >= low.value : v > low.value);
  const bool highOk = !high.bounded || (high.inclusive ? v <= high.value : v < high.value);
  if (lowOk && highOk) {
    out = v;
    return {};
  }
  if (low.bounded && high.bounded)
    return s + " is outside " + (low.inclusive ? "[" : "(") + number(low.value) + ", " + number(high.value) +
           (high.inclusive ? "]" : ")") + suffix;
  if (low.bounded) {
    if (!low.inclusive) return s + " must be greater than " + number(low.value) + suffix;
    if (low.value == 0.0) return s + " is negative; give 0 or more" + suffix;
    return s + " is below " + number(low.value) + "; give " + number(low.value) + " or more" + suffix;
  }
  if (!high.inclusive) return s + " must be less than " + number(high.value) + suffix;
  return s + " is above " + number(high.value) + "; give " + number(high.value) + " or less" + suffix;
}

CLI::Validator realNumber(Bound low, Bound high, const std::string& suffix) {
  std::string desc;
  if (low.bounded && high.bounded)
    desc = std::string(low.inclusive ? "[" : "(") + number(low.value) + ", " + number(high.value) +
           (high.inclusive ? "]" : ")");
  else if (low.bounded)
    desc = std::string(low.inclusive ? ">= " : "> ") + number(low.value);
  else if (high.bounded)
    desc = std::string(high.inclusive ? "<= " : "< ") + number(high.value);
  return CLI::Validator(
      [low, high, suffix](std::string& value) {
        double v = 0.0;
        return parseReal(value, low, high, suffix, v);
      },
      desc);
}

std::string parseFloatReal(std::string_view text, Bound low, Bound high, const std::string& suffix, float& out) {
  double v = 0.0;
  if (std::string e = parseReal(text, {}, {}, suffix, v); !e.empty()) return e;
  const float f = float(v);
  if (!std::isfinite(f))
    return quote(text) + " is too large for a 32-bit float (magnitude above " + number(kFloatMax) + ")";
  // The bounds apply to the value the option gets: 1e-50 is 0 as a float.
  double rounded = 0.0;
  if (std::string e = parseReal(number17(f), low, high, suffix, rounded); !e.empty()) {
    std::string m = parseReal(text, low, high, suffix, rounded);
    if (m.empty()) m = std::string(text) + " is " + number(f) + " as a 32-bit float, which" + e.substr(e.find(' '));
    return m;
  }
  out = f;
  return {};
}

CLI::Validator floatNumber(Bound low, Bound high, const std::string& suffix) {
  CLI::Validator v = realNumber(low, high, suffix);
  const std::string desc = v.get_description();
  return CLI::Validator(
      [low, high, suffix](std::string& value) {
        float f = 0.0f;
        return parseFloatReal(value, low, high, suffix, f);
      },
      desc);
}

CLI::Validator nonEmpty(const std::string& what) {
  return CLI::Validator(
      [what](std::string& value) { return value.empty() ? "the " + what + " is empty" : std::string(); }, "");
}

CLI::Validator oneOf(std::vector<std::string> names) {
  return CLI::Validator(
      [names](std::string& value) -> std::string {
        for (const std::string& n : names)
          if (value == n) return {};
        return quote(value) + " is not " + joinNames(names);
      },
      "");
}

std::string parseNumberList(std::string_view text, size_t count, std::vector<float>& out) {
  out.clear();
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = text.find(',', start);
    const std::string_view item = text.substr(start,
                                              comma == std::string_view::npos ? std::string_view::npos : comma - start);
    float v = 0.0f;
    if (std::string e = floatItemError(item, v); !e.empty()) return quote(item) + " in " + quote(text) + e;
    out.push_back(v);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  if (out.size() != count)
    return "expected " + std::to_string(count) + " comma-separated numbers, got " + std::to_string(out.size()) +
           " in " + quote(text);
  return {};
}

CLI::Validator numberList(size_t count) {
  return CLI::Validator(
      [count](std::string& value) {
        std::vector<float> list;
        return parseNumberList(value, count, list);
      },
      "");
}

std::string parseWholeNumberList(std::string_view text, uint64_t min, uint64_t max, std::vector<uint32_t>& out) {
  std::vector<uint32_t> list;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = text.find(',', start);
    const std::string_view item = text.substr(start,
                                              comma == std::string_view::npos ? std::string_view::npos : comma - start);
    uint64_t v = 0;
    if (!parseWhole(item, v))
      return quote(item) + " in " + quote(text) + " is not a whole number in " + range(min, max);
    if (v < min || v > max) return std::string(item) + " in " + quote(text) + " is outside " + range(min, max);
    list.push_back(uint32_t(v));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  out = std::move(list);
  return {};
}

std::string parseSize(std::string_view text, uint32_t min, uint32_t max, uint32_t& width, uint32_t& height) {
  const size_t x = text.find('x');
  uint64_t w = 0, h = 0;
  if (x == std::string_view::npos || !parseWhole(text.substr(0, x), w) || !parseWhole(text.substr(x + 1), h))
    return quote(text) + " is not WxH (e.g. 1280x720)";
  if (w < min || w > max)
    return "width " + std::string(text.substr(0, x)) + " in " + quote(text) + " is outside " + range(min, max);
  if (h < min || h > max)
    return "height " + std::string(text.substr(x + 1)) + " in " + quote(text) + " is outside " + range(min, max);
  width = uint32_t(w);
  height = uint32_t(h);
  return {};
}

std::string parseNameSet(std::string_view text, const std::vector<std::string>& names, std::string_view what,
                         uint32_t& out) {
  uint32_t set = 0;
  size_t start = 0;
  while (!text.empty() && start <= text.size()) {
    const size_t comma = text.find(',', start);
    const std::string_view item = text.substr(start,
                                              comma == std::string_view::npos ? std::string_view::npos : comma - start);
    size_t i = 0;
    while (i < names.size() && names[i] != item) ++i;
    if (i == names.size())
      return quote(item) + " in " + quote(text) + " is not " + std::string(what) + " (" + joinNames(names, ", ") + ")";
    set |= 1u << i;
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  out = set;
  return {};
}

void prepare(CLI::App& app) {
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.get_formatter()->column_width(34);
}

std::string parse(CLI::App& app, int argc, const char* const* argv, bool& help) {
  help = false;
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    help = true;
  } catch (const CLI::CallForAllHelp&) {
    help = true;
  } catch (const CLI::ExtrasError& e) {
    const std::vector<std::string> rest = app.remaining();
    if (rest.empty()) return e.what();
    return (rest[0].size() > 1 && rest[0][0] == '-' ? "unknown option " : "unexpected argument ") + quote(rest[0]);
  } catch (const CLI::ArgumentMismatch& e) {
    // "--width: 1 required W:1..16384 missing" reads better as "--width needs a value (W:1..16384)".
    const std::string what = e.what();
    const size_t colon = what.find(": "), required = what.find(" required "), missing = what.rfind(" missing");
    if (colon == std::string::npos || required == std::string::npos || missing != what.size() - 8) return what;
    return what.substr(0, colon) + " needs a value (" + what.substr(required + 10, missing - required - 10) + ")";
  } catch (const CLI::ParseError& e) {
    return e.what();
  }
  return {};
}

std::string commandLine(int argc, const char* const* argv) {
  std::string s;
  for (int i = 0; i < argc; ++i) {
    if (i) s += ' ';
    s += argv[i];
  }
  return s;
}

}  // namespace rbCli
