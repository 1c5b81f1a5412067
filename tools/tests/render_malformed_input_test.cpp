// raybridge-render's malformed input (issue 12): every option value, input file and output folder that cannot work
// gives a non-zero exit and a message naming the option, the value and what is valid; never a crash, a hang or a
// validation error, and no image. Each row runs the real executable, without a shell (the arguments reach it as
// written, empty ones included), under a time limit; a signal, a timeout, a validation error or a sanitizer report
// fails the row. Most rows fail while parsing (exit 2) or while checking the files (exit 1), before any Vulkan work;
// only the rows of a write that fails after the render render (16x16, raster).
#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch_test_macros.hpp>
#include <nlohmann/json.hpp>

extern char** environ;

namespace fs = std::filesystem;

namespace {

// The render command built with these tests; RAYBRIDGE_RENDER overrides it where the binaries were moved.
std::string renderExecutable() {
  const char* overridden = std::getenv("RAYBRIDGE_RENDER");
  return overridden && *overridden ? overridden : RAYBRIDGE_RENDER_EXE;
}

// A failing run ends within seconds (a render of 16x16 pixels under ASan on lavapipe within a minute); past this
// limit the run counts as a hang and is killed.
constexpr int kTimeLimitSeconds = 300;

struct Run {
  int exitCode = -1;  // when it exited
  int signal = 0;     // when a signal ended it
  bool timedOut = false;
  std::string output;  // stdout and stderr
  std::string commandLine;
};

// Runs raybridge-render --validation ARGS with stdout and stderr into one pipe, killing it at the time limit.
Run runRender(const std::vector<std::string>& args) {
  std::vector<std::string> all = {renderExecutable(), "--validation"};
  all.insert(all.end(), args.begin(), args.end());
  Run r;
  for (const std::string& a : all) {
    if (!r.commandLine.empty()) r.commandLine += ' ';
    r.commandLine.append(1, '\'').append(a).append(1, '\'');
  }
  std::vector<char*> argv;
  for (std::string& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);

  int fds[2];
  REQUIRE(pipe2(fds, O_CLOEXEC) == 0);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDERR_FILENO);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[1]);
  if (spawned != 0) close(fds[0]);
  REQUIRE(spawned == 0);

  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(kTimeLimitSeconds);
  char buffer[4096];
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline -
                                                                            std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      r.timedOut = true;
      kill(pid, SIGKILL);
      break;
    }
    pollfd p{fds[0], POLLIN, 0};
    const int ready = poll(&p, 1, int(left.count()));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) continue;  // the deadline check above ends the wait
    const ssize_t n = read(fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;  // end of output: the program closed its ends (it exited)
    r.output.append(buffer, size_t(n));
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status)) r.exitCode = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) r.signal = WTERMSIG(status);
  return r;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

fs::path tempDir(const std::string& name) {
  fs::path dir = fs::temp_directory_path() / ("raybridge_malformed_input_tests_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void writeFile(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
  REQUIRE(fs::file_size(path) == bytes.size());
}

std::string randomBytes(size_t count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::string s(count, '\0');
  for (char& c : s) c = char(rng() & 0xff);
  return s;
}

// Exit statuses of raybridge-render: 2 = the command line is wrong (printed with the usage), 1 = what it names
// cannot be used (a file, a folder, a device), 3 = the validation layer reported errors.
constexpr int kBadCommandLine = 2, kBadInput = 1;

struct Row {
  std::vector<std::string> args;
  std::string expected;  // part of the message after "raybridge-render: error: "
  int exitCode = kBadCommandLine;
};

// The folder the row's output would go to: the last --out (a repeated option keeps its last value).
fs::path outputOf(const std::vector<std::string>& args) {
  fs::path out;
  for (size_t i = 0; i + 1 < args.size(); ++i)
    if (args[i] == "--out") out = args[i + 1];
  return out;
}

// What every failing run must show: it exited (no signal, no hang) with the row's status, printed the message, no
// validation error and no sanitizer report, and wrote no image.
void checkFailure(const Run& r, const Row& row, const fs::path& out) {
  INFO(r.commandLine << "\n" << r.output);
  CHECK_FALSE(r.timedOut);
  CHECK(r.signal == 0);
  CHECK(r.exitCode == row.exitCode);
  CHECK(contains(r.output, "raybridge-render: error: " + row.expected));
  CHECK_FALSE(contains(r.output, "validation error]"));
  CHECK_FALSE(contains(r.output, "Sanitizer"));
  CHECK_FALSE(contains(r.output, "runtime error:"));
  if (!out.empty()) {
    std::error_code ec;
    CHECK_FALSE(fs::exists(out / "final.png", ec));
    CHECK_FALSE(fs::exists(out / "final.exr", ec));
  }
}

// Runs each row with --out DIR/out before its own arguments (a row's own --out comes later and wins).
void runRows(const std::vector<Row>& rows, const fs::path& dir) {
  for (const Row& row : rows) {
    std::vector<std::string> args = {"--out", (dir / "out").string()};
    args.insert(args.end(), row.args.begin(), row.args.end());
    checkFailure(runRender(args), row, outputOf(args));
  }
}

// A whole-number option: its range as the messages write it and what 0 means where 0 is allowed.
struct WholeOption {
  std::string name;
  uint64_t min, max;
  std::string zeroMeaning;  // "" = 0 is outside the range
};

const std::vector<WholeOption> kWholeOptions = {
    {"--width", 1, 16384, ""},
    {"--height", 1, 16384, ""},
    {"--shadow-rays", 1, 4096, ""},
    {"--ao-rays", 1, 4096, ""},
    {"--reflection-rays", 1, 64, ""},
    {"--light-rays", 1, 64, "exact"},
    {"--shadow-map-size", 1024, 8192, "no shadow map"},
    {"--pcf", 1, 9, ""},
    {"--frames", 1, 100000, ""},
    {"--characters", 1, 1000, ""},
    {"--perf-ground", 1, 4096, ""},
    {"--perf-copies", 1, 256, ""},
};

}  // namespace

TEST_CASE("raybridge-render: whole-number options reject every malformed count, naming the range",
          "[render][bad-input][malformed]") {
  const fs::path dir = tempDir("whole");
  std::vector<Row> rows;
  for (const WholeOption& w : kWholeOptions) {
    const std::string range = std::to_string(w.min) + ".." + std::to_string(w.max);
    const std::string zero = w.zeroMeaning.empty() ? "" : " (or 0 = " + w.zeroMeaning + ")";
    const std::string prefix = w.name + ": ";
    for (const char* v : {"", "1.5x", "1,2,3,", "-1", "+5", " 5", "5 ", "nan", "inf", "1e3", "0x10", "5.0"})
      rows.push_back({{w.name, v}, prefix + "'" + v + "' is not a whole number in " + range + zero});
    // Too large for any integer type, and the sizes the issue names.
    rows.push_back({{w.name, "99999999999999999999"}, prefix + "99999999999999999999 is outside " + range + zero});
    rows.push_back({{w.name, std::string(400, '9')}, prefix + std::string(400, '9') + " is outside " + range + zero});
    const std::string tooMany = w.max == 100000 ? "100001" : "100000";  // --frames goes up to 100000
    rows.push_back({{w.name, tooMany}, prefix + tooMany + " is outside " + range + zero});
    if (w.zeroMeaning.empty()) rows.push_back({{w.name, "0"}, prefix + "0 is outside " + range});
    // CLI11 would read a leading zero as octal ("010" = 8) or fail on it ("09").
    std::string leading = "0";
    leading += std::to_string(w.min);
    rows.push_back({{w.name, leading},
                    prefix + "'" + leading + "' has a leading zero; give " + std::to_string(w.min) + " (" + range +
                        (w.zeroMeaning.empty() ? "" : ", or 0 = " + w.zeroMeaning) + ")"});
    rows.push_back({{w.name}, w.name + " needs a value"});  // the value is missing at the end
  }
  // A first value that is bad fails even when a later one would do (every value given is checked).
  rows.push_back({{"--width", "0", "--width", "64"}, "--width: 0 is outside 1..16384"});
  rows.push_back({{"--width", "16384", "--height", "16384"}, "--width/--height: 16384x16384 exceeds 67 megapixels"});
  runRows(rows, dir);
}

TEST_CASE("raybridge-render: real-number options reject non-finite, malformed and out-of-range values",
          "[render][bad-input][malformed]") {
  const fs::path dir = tempDir("real");
  struct RealOption {
    std::string name;
    std::vector<std::pair<std::string, std::string>> outOfRange;  // value, message after "--name: "
  };
  const std::vector<RealOption> options = {
      {"--time", {{"-1", "-1 is negative; give 0 or more"}, {"-1e-300", "-1e-300 is negative; give 0 or more"}}},
      {"--fps",
       {{"0", "0 must be greater than 0"},
        {"-0", "-0 must be greater than 0"},
        {"-5", "-5 must be greater than 0"},
        {"1e-400", "1e-400 must be greater than 0"}}},
      {"--sun-radius",
       {{"-1", "-1 is outside [0, 45) degrees"},
        {"45", "45 is outside [0, 45) degrees"},
        {"100000", "100000 is outside [0, 45) degrees"},
        {"44.999999999", "44.999999999 is 45 as a 32-bit float, which is outside [0, 45) degrees"}}},
      {"--ao-range",
       {{"0", "0 must be greater than 0 (world units)"},
        {"1e-400", "1e-400 must be greater than 0 (world units)"},
        {"1e-50", "1e-50 is 0 as a 32-bit float, which must be greater than 0 (world units)"},
        {"1e39", "'1e39' is too large for a 32-bit float (magnitude above 3.40282e+38)"}}},
      {"--reflection-roughness",
       {{"0", "0 is outside (0, 1]"},
        {"1.0000001", "1.0000001 is outside (0, 1]"},
        {"1e-50", "1e-50 is 0 as a 32-bit float, which is outside (0, 1]"}}},
  };
  std::vector<Row> rows;
  for (const RealOption& o : options) {
    const std::string prefix = o.name + ": ";
    for (const char* v : {"nan", "-nan", "NaN", "inf", "-inf", "infinity", "1e999", "-1e999", "0x1p2000"})
      rows.push_back({{o.name, v}, prefix + "'" + v + "' is not finite; give a finite number"});
    for (const char* v : {"", "1.5x", "1,2,3,", "1,5", " 1", "1 ", "abc", "0x", "1e", "--1"})
      rows.push_back({{o.name, v}, prefix + "'" + v + "' is not a number"});
    for (const auto& [value, message] : o.outOfRange) rows.push_back({{o.name, value}, prefix + message});
    rows.push_back({{o.name}, o.name + " needs a value"});
  }
  runRows(rows, dir);
}

TEST_CASE("raybridge-render: --camera and --sun reject non-finite components and degenerate cameras",
          "[render][bad-input][malformed]") {
  const fs::path dir = tempDir("vectors");
  std::vector<Row> rows;
  // Every component of both vectors, each kind of bad number.
  const std::vector<std::pair<std::string, std::string>> badNumbers = {
      {"nan", "is not finite; give a finite number"},
      {"inf", "is not finite; give a finite number"},
      {"-inf", "is not finite; give a finite number"},
      {"1e999", "is not finite; give a finite number"},
      {"0x1p2000", "is not finite; give a finite number"},
      {"1e39", "is too large for a 32-bit float (magnitude above 3.40282e+38)"},
      {"1.5x", "is not a number"},
  };
  for (const auto& [option, base] :
       {std::pair<std::string, std::vector<std::string>>{"--camera", {"0", "2", "8", "0", "0", "0", "45"}},
        std::pair<std::string, std::vector<std::string>>{"--sun", {"0.3", "1", "0.2"}}}) {
    for (size_t i = 0; i < base.size(); ++i) {
      for (const auto& [bad, message] : badNumbers) {
        std::vector<std::string> items = base;
        items[i] = bad;
        std::string list;
        for (const std::string& item : items) list += (list.empty() ? "" : ",") + item;
        rows.push_back({{option, list}, option + ": '" + bad + "' in '" + list + "' " + message});
      }
    }
  }
  const std::vector<Row> more = {
      // The list itself.
      {{"--camera", ""}, "--camera: '' in '' is not a number"},
      {{"--camera", "0,2,8,0,0,0"}, "--camera: expected 7 comma-separated numbers, got 6 in '0,2,8,0,0,0'"},
      {{"--camera", "0,2,8,0,0,0,45,1"}, "--camera: expected 7 comma-separated numbers, got 8"},
      {{"--camera", "0,2,8,0,0,0,45,"}, "--camera: '' in '0,2,8,0,0,0,45,' is not a number"},
      {{"--camera", "0;2;8;0;0;0;45"}, "--camera: '0;2;8;0;0;0;45' in '0;2;8;0;0;0;45' is not a number"},
      {{"--sun", "1,2"}, "--sun: expected 3 comma-separated numbers, got 2 in '1,2'"},
      {{"--sun", ""}, "--sun: '' in '' is not a number"},
      {{"--camera"}, "--camera needs a value"},
      {{"--sun"}, "--sun needs a value"},
      // Degenerate cameras: no view direction, a field of view that gives no projection, coordinates whose squares
      // overflow a float.
      {{"--camera", "1,2,3,1,2,3,45"}, "--camera: eye equals target (1,2,3,1,2,3,45); the view direction is undefined"},
      {{"--camera", "0,0,0,1e-30,0,0,45"},
       "--camera: eye and target are 1e-30 apart in '0,0,0,1e-30,0,0,45'; the view direction needs them at least "
       "1e-06 apart"},
      {{"--camera", "1e9,0,0,999999999.9,0,0,45"}, "--camera: eye equals target"},  // equal as floats
      {{"--camera", "1e9,0,0,999999100,0,0,45"},                                    // 999999104 as a float
       "--camera: eye and target are 896 apart in '1e9,0,0,999999100,0,0,45'; the view direction needs them at least "
       "1000 apart"},
      {{"--camera", "0,2,8,0,0,0,0"}, "--camera: fovy 0 is outside [0.01, 180) degrees"},
      {{"--camera", "0,2,8,0,0,0,-45"}, "--camera: fovy -45 is outside [0.01, 180) degrees"},
      {{"--camera", "0,2,8,0,0,0,180"}, "--camera: fovy 180 is outside [0.01, 180) degrees"},
      {{"--camera", "0,2,8,0,0,0,100000"}, "--camera: fovy 100000 is outside [0.01, 180) degrees"},
      {{"--camera", "0,2,8,0,0,0,1e-40"}, "--camera: fovy 1e-40 is outside [0.01, 180) degrees"},
      {{"--camera", "1e10,2,8,0,0,0,45"},
       "--camera: ex 1e10 is outside [-1e+09, 1e+09] (world units) in '1e10,2,8,0,0,0,45'"},
      {{"--camera", "0,2,8,0,0,-3e38,45"}, "--camera: tz -3e38 is outside [-1e+09, 1e+09] (world units)"},
      {{"--sun", "0,0,0"}, "--sun: the direction 0,0,0 has zero length; give a direction towards the sun"},
      {{"--sun", "-0,0,-0"}, "--sun: the direction -0,0,-0 has zero length"},
      {{"--sun", "1e-50,0,0"}, "--sun: the direction 1e-50,0,0 has zero length"},  // 0 as a float
      // A repeated option keeps its last value, but every value given is checked.
      {{"--camera", "0,2,8,0,0,0,45", "--camera", "0,2,8,0,0,0,0"}, "--camera: fovy 0 is outside"},
      {{"--camera", "0,2,8,0,0,0,0", "--camera", "0,2,8,0,0,0,45"}, "--camera: fovy 0 is outside"},
      {{"--sun", "0,0,0", "--sun", "0.3,1,0.2"}, "--sun: the direction 0,0,0 has zero length"},
  };
  rows.insert(rows.end(), more.begin(), more.end());
  runRows(rows, dir);
}

TEST_CASE("raybridge-render: unknown names, empty values and combinations that cannot work",
          "[render][bad-input][malformed]") {
  const fs::path dir = tempDir("names");
  const std::string presets = "(none, hard-shadows, ao, ao16, reflections, soft-shadows, soft-shadows8, low, medium, "
                              "high, ultra)";
  const std::string effects = "(shadows, ao, reflections, lights)";
  std::vector<Row> rows;
  for (const char* v : {"High", "HIGH", "", " high", "high ", "nonsense", "high,low", "soft_shadows"})
    rows.push_back({{"--preset", v}, std::string("--preset: '") + v + "' is not a preset " + presets});
  const std::vector<Row> more = {
      {{"--effects", "bogus"}, "--effects: 'bogus' in 'bogus' is not an effect " + effects},
      {{"--effects", "AO"}, "--effects: 'AO' in 'AO' is not an effect " + effects},
      {{"--effects", "ao,"}, "--effects: '' in 'ao,' is not an effect " + effects},
      {{"--effects", ",ao"}, "--effects: '' in ',ao' is not an effect " + effects},
      {{"--effects", "shadows;ao"}, "--effects: 'shadows;ao' in 'shadows;ao' is not an effect " + effects},
      {{"--effects", "none,ao"}, "--effects: 'none' in 'none,ao' is not an effect " + effects},
      {{"--half-res", "shadows"},
       "--half-res: 'shadows' in 'shadows' is not an effect with half-resolution tracing (ao, reflections)"},
      {{"--half-res", "AO"}, "--half-res: 'AO' in 'AO' is not an effect with half-resolution tracing"},
      {{"--half-res", "ao,"}, "--half-res: '' in 'ao,' is not an effect with half-resolution tracing"},
      {{"--adaptive", ""}, "--adaptive: '' in '' is not an effect with adaptive rays (shadows, ao)"},
      {{"--adaptive", "AO"}, "--adaptive: 'AO' in 'AO' is not an effect with adaptive rays (shadows, ao)"},
      {{"--adaptive", "ao,"}, "--adaptive: '' in 'ao,' is not an effect with adaptive rays"},
      {{"--adaptive", "ao="}, "--adaptive: '' in 'ao=' is not a time in ms greater than 0"},
      {{"--adaptive", "ao=nan"}, "--adaptive: 'nan' in 'ao=nan' is not a time in ms greater than 0"},
      {{"--adaptive", "ao=inf"}, "--adaptive: 'inf' in 'ao=inf' is not a time in ms greater than 0"},
      {{"--adaptive", "ao=1e999"}, "--adaptive: '1e999' in 'ao=1e999' is not a time in ms greater than 0"},
      {{"--adaptive", "ao=1e39"}, "--adaptive: '1e39' in 'ao=1e39' is not a time in ms greater than 0"},
      {{"--adaptive", "ao=1e-400"}, "--adaptive: '1e-400' in 'ao=1e-400' is not a time in ms greater than 0"},
      {{"--adaptive", "ao=0"}, "--adaptive: '0' in 'ao=0' is not a time in ms greater than 0"},
      {{"--adaptive", "ao=1.5x"}, "--adaptive: '1.5x' in 'ao=1.5x' is not a time in ms greater than 0"},
      {{"--adaptive", "ao=1=2"}, "--adaptive: '1=2' in 'ao=1=2' is not a time in ms greater than 0"},
      {{"--adaptive", "ao,tile=16x4"}, "--adaptive: '16x4' in 'tile=16x4' is not a tile WxH with sides 1, 2, 4 or 8"},
      {{"--adaptive", "ao,tile=8"}, "--adaptive: '8' in 'tile=8' is not a tile WxH with sides 1, 2, 4 or 8"},
      {{"--adaptive", "ao,tile=0x4"}, "--adaptive: '0x4' in 'tile=0x4' is not a tile WxH with sides 1, 2, 4 or 8"},
      {{"--adaptive", "ao,tile=8x"}, "--adaptive: '8x' in 'tile=8x' is not a tile WxH with sides 1, 2, 4 or 8"},
      {{"--adaptive", "ao,tile=-8x4"}, "--adaptive: '-8x4' in 'tile=-8x4' is not a tile WxH"},
      {{"--adaptive", "tile=8x4"}, "--adaptive: 'tile=8x4' names no effect with adaptive rays (shadows, ao)"},
      {{"--ao-estimator", "cosine"}, "--ao-estimator: 'cosine' is not binary or distance"},
      {{"--ao-estimator", "Binary"}, "--ao-estimator: 'Binary' is not binary or distance"},
      {{"--ao-estimator", ""}, "--ao-estimator: '' is not binary or distance"},
      {{"--mode", "Raster"}, "--mode: 'Raster' is not raster, hybrid or raytraced"},
      {{"--mode", "ray-traced"}, "--mode: 'ray-traced' is not raster, hybrid or raytraced"},
      {{"--mode", ""}, "--mode: '' is not raster, hybrid or raytraced"},
      {{"--gbuffer-normals", "flat"}, "--gbuffer-normals: 'flat' is not shading or geometric"},
      {{"--dynamic-builds", "async_late"}, "--dynamic-builds: 'async_late' is not in-frame, async or async-late"},
      {{"--dynamic-builds", ""}, "--dynamic-builds: '' is not in-frame, async or async-late"},
      {{"--preset"}, "--preset needs a value"},
      {{"--mode"}, "--mode needs a value"},
      // Empty names of files and folders.
      {{"--scene", ""}, "--scene: the file name is empty"},
      {{"--camera-path", ""}, "--camera-path: the file name is empty"},
      {{"--out", ""}, "--out: the folder name is empty"},
      {{"--models-from", ""}, "--models-from: the folder name is empty"},
      {{"--animation", ""}, "--animation: the index or name is empty"},
      {{"--out"}, "--out needs a value"},
      // Unknown options and arguments.
      {{"--frobnicate"}, "unknown option '--frobnicate'"},
      {{"--Width", "64"}, "unknown option '--Width'"},
      {{"-w", "64"}, "unknown option '-w'"},
      {{"stray"}, "unexpected argument 'stray'"},
      {{"--preset", "high", "--preset", "bogus"}, "--preset: 'bogus' is not a preset"},
      // Combinations that cannot work.
      {{"--camera-path", "x.json", "--camera", "0,2,8,0,0,0,45"},
       "--camera-path and --camera both set the camera; give only one of them"},
      {{"--characters", "2", "--scene", "x.gltf"}, "--characters: adds characters to the demo scene"},
      {{"--characters", "2", "--animation", "walk"},
       "--animation: with --characters every character plays its own animation; drop --animation"},
      {{"--perf-scene", "--scene", "x.gltf"}, "--perf-scene is a scene of its own"},
      {{"--perf-ground", "8"}, "--perf-ground, --perf-copies and --perf-ground-only shape the performance scene"},
      {{"--perf-scene", "--perf-ground-only", "--perf-copies", "2"},
       "--perf-copies: --perf-ground-only places no model to copy"},
      {{"--models-from", "/tmp"}, "--models-from needs --characters N or --perf-scene"},
      {{"--mode", "raytraced", "--effects", "ao"}, "--effects: --mode raytraced shades every primary ray"},
      {{"--mode", "raytraced", "--gbuffer-normals", "geometric"},
       "--gbuffer-normals: --mode raytraced draws no G-buffer"},
      {{"--adaptive", "ao", "--no-denoise"}, "--adaptive: adaptive rays plan from the denoiser's history"},
      {{"--adaptive", "ao", "--mode", "raster"}, "--adaptive: only --mode hybrid traces the shadow and AO passes"},
  };
  rows.insert(rows.end(), more.begin(), more.end());
  runRows(rows, dir);
}

TEST_CASE("raybridge-render: input files that are missing, folders, empty, random or endless name the problem",
          "[render][bad-input][malformed]") {
  const fs::path dir = tempDir("inputs");
  const std::string d = dir.string() + "/";
  fs::create_directories(dir / "folder.gltf");
  fs::create_directories(dir / "folder.json");
  fs::create_directories(dir / "models");
  writeFile(dir / "empty.gltf", "");
  writeFile(dir / "empty.glb", "");
  writeFile(dir / "empty.json", "");
  writeFile(dir / "random.gltf", randomBytes(4096, 1));
  writeFile(dir / "random.glb", randomBytes(4096, 2));
  writeFile(dir / "random.json", randomBytes(4096, 3));
  writeFile(dir / "truncated.gltf", R"({ "asset": { "version": "2.0" }, "meshes": [ { "primitives": )");
  writeFile(dir / "no_meshes.gltf", R"({ "asset": { "version": "2.0" } })");
  // One triangle, no animation.
  writeFile(dir / "triangle.gltf", R"({"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)"
                                   R"("meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],)"
                                   R"("accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",)"
                                   R"("min":[0,0,0],"max":[1,1,0]}],"bufferViews":[{"buffer":0,"byteLength":36}],)"
                                   R"("buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,)"
                                   R"(AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}]})");
  writeFile(dir / "far.json", R"({"version":1,"keyframes":[{"position":[1e20,2,8],"orientation":[0,0,0,1]}]})");
  writeFile(dir / "narrow.json",
            R"({"version":1,"fovy_degrees":0.001,"keyframes":[{"position":[0,2,8],"orientation":[0,0,0,1]}]})");
  writeFile(dir / "file", "not a folder\n");
  REQUIRE(mkfifo((dir / "fifo").c_str(), 0600) == 0);  // opening it for reading would wait for a writer forever

  const std::vector<Row> rows = {
      {{"--scene", d + "missing.gltf"}, "--scene: file '" + d + "missing.gltf' does not exist", kBadInput},
      {{"--scene", d + "folder.gltf"}, "--scene: '" + d + "folder.gltf' is a folder, not a glTF file", kBadInput},
      {{"--scene", d + "empty.gltf"},
       "--scene: cannot load glTF '" + d + "empty.gltf': glTF '" + d + "empty.gltf' is empty",
       kBadInput},
      {{"--scene", d + "empty.glb"}, "--scene: cannot load glTF '" + d + "empty.glb'", kBadInput},
      {{"--scene", d + "random.gltf"}, "--scene: cannot load glTF '" + d + "random.gltf': failed to parse", kBadInput},
      {{"--scene", d + "random.glb"}, "--scene: cannot load glTF '" + d + "random.glb': failed to parse", kBadInput},
      {{"--scene", d + "truncated.gltf"}, "--scene: cannot load glTF '" + d + "truncated.gltf'", kBadInput},
      {{"--scene", d + "no_meshes.gltf"},
       "--scene: cannot load glTF '" + d + "no_meshes.gltf': glTF '" + d +
           "no_meshes.gltf' contains no renderable triangles",
       kBadInput},
      {{"--scene", "/dev/zero"}, "--scene: '/dev/zero' is not a regular file; give a glTF file", kBadInput},
      {{"--scene", d + "fifo"}, "--scene: '" + d + "fifo' is not a regular file", kBadInput},
      {{"--scene", d + "missing1.gltf", "--scene", d + "missing2.gltf"},
       "--scene: file '" + d + "missing2.gltf' does not exist",
       kBadInput},
      {{"--scene", d + "triangle.gltf", "--animation", "walk"},
       "--animation walk: the scene has no animations",
       kBadInput},
      {{"--animation", "0"}, "--animation 0: the scene has no animations", kBadInput},  // the demo scene
      {{"--camera-path", d + "missing.json"},
       "--camera-path: '" + d + "missing.json': cannot be opened: No such file or directory",
       kBadInput},
      {{"--camera-path", d + "folder.json"},
       "--camera-path: '" + d + "folder.json': is a folder, not a camera path file",
       kBadInput},
      {{"--camera-path", d + "empty.json"}, "--camera-path: '" + d + "empty.json': is empty", kBadInput},
      {{"--camera-path", d + "random.json"}, "--camera-path: '" + d + "random.json': not JSON", kBadInput},
      {{"--camera-path", "/dev/zero"}, "--camera-path: '/dev/zero': is not a regular file", kBadInput},
      {{"--camera-path", d + "fifo"}, "--camera-path: '" + d + "fifo': is not a regular file", kBadInput},
      {{"--camera-path", d + "far.json"},
       "--camera-path: '" + d + "far.json': keyframe 0: position x 1e+20 is outside [-1e+09, 1e+09] (world units)",
       kBadInput},
      {{"--camera-path", d + "narrow.json"},
       "--camera-path: '" + d + "narrow.json': keyframe 0: fovy_degrees 0.001 is outside [0.01, 180) degrees",
       kBadInput},
      {{"--characters", "1", "--models-from", d + "file"},
       "--models-from: '" + d + "file' is not a folder; give the folder of the shared glTF models",
       kBadInput},
      {{"--perf-scene", "--models-from", d + "missing"},
       "--models-from: '" + d + "missing' does not exist; give the folder of the shared glTF models",
       kBadInput},
      {{"--characters", "1", "--models-from", d + "models"},
       "--characters: no character model found (looked for " + d + "models/CesiumMan/CesiumMan.gltf",
       kBadInput},
      {{"--perf-scene", "--models-from", d + "models"},
       "--perf-scene: no model of the performance scene found",
       kBadInput},
      // The device filter matches no device: the engine names the devices it saw.
      {{"--device", "no-such-gpu-anywhere"}, "engine: no suitable Vulkan 1.3 device found", kBadInput},
  };
  runRows(rows, dir);
}

TEST_CASE("raybridge-render: output folders that cannot be written fail before the render, naming the folder",
          "[render][bad-input][malformed]") {
  const fs::path dir = tempDir("outputs");
  const std::string d = dir.string() + "/";
  writeFile(dir / "file", "a regular file where a folder should be\n");
  // A folder whose own path fits PATH_MAX (4096 with the terminating 0), as final.png in it would, but not the
  // probe's longer name: the folder is refused before the render rather than after it (at stats.json with --dump).
  constexpr size_t kDeepLength = 4075;
  fs::path deep = dir;
  while (deep.string().size() < kDeepLength) {
    const size_t room = kDeepLength - deep.string().size() - 1;  // after the separator
    deep /= std::string(std::clamp<size_t>(room, 1, 200), 'd');
  }
  std::error_code ec;
  fs::create_directories(deep, ec);
  INFO(deep.string().size() << " " << ec.message());
  REQUIRE(fs::is_directory(deep));

  const std::string advice = "; give a folder that can be created and written to";
  const std::string tooLong(NAME_MAX + 1, 'n');
  std::string overPathMax = d;
  while (overPathMax.size() <= PATH_MAX) overPathMax += std::string(200, 'p') + "/";
  const std::vector<Row> rows = {
      {{"--out", d + "file"},
       "--out: the folder '" + d + "file' cannot be created: '" + d + "file' is a file, not a folder" + advice,
       kBadInput},
      {{"--out", d + "file/sub"},
       "--out: the folder '" + d + "file/sub' cannot be created: '" + d + "file' is a file, not a folder" + advice,
       kBadInput},
      {{"--out", d + "file/a/b/c"},
       "--out: the folder '" + d + "file/a/b/c' cannot be created: '" + d + "file' is a file, not a folder",
       kBadInput},
      {{"--out", "/proc/raybridge-render-out"},
       "--out: the folder '/proc/raybridge-render-out' cannot be created: No such file or directory" + advice,
       kBadInput},
      {{"--out", "/proc/self"}, "--out: the folder '/proc/self' cannot be written to: ", kBadInput},
      {{"--out", "/dev/null"}, "--out: the folder '/dev/null' cannot be created: '/dev/null' is a file", kBadInput},
      {{"--out", d + tooLong},
       "--out: the folder '" + d + tooLong + "' cannot be created: File name too long" + advice,
       kBadInput},
      {{"--out", overPathMax},
       "--out: the folder '" + overPathMax + "' cannot be created: File name too long" + advice,
       kBadInput},
      {{"--out", deep.string()},
       "--out: the folder '" + deep.string() + "' cannot be written to: File name too long" + advice,
       kBadInput},
  };
  runRows(rows, dir);
  // The probe file is removed wherever it could be written.
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(dir, ec))
    CHECK_FALSE(contains(e.path().filename().string(), "raybridge-render-write-test"));
}

TEST_CASE("raybridge-render: a write that fails after the render is an error naming the file, not a success",
          "[render][bad-input][malformed]") {
  // /dev/full takes the open and fails the write (ENOSPC): a full disk after the start-up probe. Each file the
  // command writes is in turn a link to it.
  const fs::path dir = tempDir("full");
  const std::vector<std::string> render = {"--width", "16",     "--height", "16",       "--frames",
                                           "1",       "--mode", "raster",   "--preset", "none"};
  for (const char* name : {"final.png", "final.exr", "stats.json", "depth.exr"}) {
    const fs::path out = dir /
                         ("full_" + fs::path(name).stem().string() + fs::path(name).extension().string().substr(1));
    fs::create_directories(out);
    fs::create_symlink("/dev/full", out / name);
    std::vector<std::string> args = render;
    args.insert(args.end(), {"--dump", "--out", out.string()});
    const Run r = runRender(args);
    INFO(r.commandLine << "\n" << r.output);
    CHECK_FALSE(r.timedOut);
    CHECK(r.signal == 0);
    CHECK(r.exitCode == kBadInput);
    CHECK(contains(r.output, "raybridge-render: error: "));
    CHECK(contains(r.output, "cannot write " + (out / name).string() + ": No space left on device"));
    CHECK_FALSE(contains(r.output, "validation error]"));
    CHECK_FALSE(contains(r.output, "Sanitizer"));
    CHECK_FALSE(contains(r.output, "runtime error:"));
    // The lines that report success ("wrote ...") never name the file that failed.
    std::istringstream lines(r.output);
    for (std::string line; std::getline(lines, line);)
      if (line.rfind("wrote", 0) == 0) CHECK_FALSE(contains(line, name));
    CHECK_FALSE(contains(r.output, "validation errors: 0"));  // the report of a finished run
    CHECK(fs::is_symlink(out / name));                        // not replaced by a partial file
  }
}

TEST_CASE("raybridge-render: edge values that are valid render without error", "[render][bad-input][malformed]") {
  // Straight down (the engine's camera nudges its up vector), a sun direction whose squared length overflows a
  // float, a hex float and a repeated option (the last wins): all render, with finite values in stats.json, and
  // the start-up probe leaves no file behind.
  const fs::path dir = tempDir("edges");
  const Run r = runRender({"--camera", "0,6,0,0,0,0,45", "--sun", "1e30,1e30,1e30", "--sun-radius", "0x1p-2",
                           "--preset", "hard-shadows", "--width", "64", "--width", "16", "--height", "16", "--frames",
                           "1", "--dump", "--out", dir.string()});
  INFO(r.commandLine << "\n" << r.output);
  REQUIRE_FALSE(r.timedOut);
  REQUIRE(r.signal == 0);
  REQUIRE(r.exitCode == 0);
  CHECK_FALSE(contains(r.output, "validation error]"));
  std::ifstream in(dir / "stats.json");
  const nlohmann::json stats = nlohmann::json::parse(in, nullptr, false);
  REQUIRE_FALSE(stats.is_discarded());
  CHECK(stats["width"] == 16);
  for (int c = 0; c < 3; ++c) {
    CHECK(stats["sun"]["direction"][c].is_number());  // a NaN would be written as null
    CHECK(stats["sun"]["direction"][c].get<double>() > 0.57);
    CHECK(stats["camera"]["eye"][c].is_number());
  }
  CHECK(stats["sun"]["angular_radius_degrees"] == 0.25);
  CHECK(stats["validation"]["errors"] == 0);
  for (const fs::directory_entry& e : fs::directory_iterator(dir))
    CHECK_FALSE(contains(e.path().filename().string(), "raybridge-render-write-test"));
}
