// The command-line contract: exit codes, one "error:" line, no output file on failure.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <csignal>
#include <sys/wait.h>

namespace fs = std::filesystem;

namespace {
struct CliRun { int code; std::string err; };
CliRun run(const std::string& args) {
  const fs::path err = fs::temp_directory_path() / ("polysquare_cli_err_" + std::to_string(::getpid()));
  const std::string cmd = std::string(POLYSQUARE_CLI) + " " + args + " > /dev/null 2> " + err.string();
  const int status = std::system(cmd.c_str());
  std::ifstream in(err);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  fs::remove(err);
  return {WEXITSTATUS(status), text};
}
std::string data(const std::string& rel) { return std::string(POLYSQUARE_DATA_DIR) + "/" + rel; }
std::string bad(const std::string& rel) { return std::string(POLYSQUARE_TEST_DATA_DIR) + "/bad/" + rel; }
}  // namespace

TEST(Cli, MeshWritesMeshReportAndPicture) {
  const fs::path dir = fs::temp_directory_path() / ("polysquare_cli_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const CliRun r = run("mesh " + data("cases/pentagon.geojson") + " --size 3 -o " + (dir / "m.msh").string() + " --report " +
                    (dir / "r.json").string() + " --picture " + (dir / "p.svg").string());
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::file_size(dir / "m.msh") > 1000);
  std::ifstream rep(dir / "r.json");
  std::string text((std::istreambuf_iterator<char>(rep)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"interior_singularities\": 0"), std::string::npos);
  EXPECT_NE(text.find("\"seconds\""), std::string::npos);
  EXPECT_TRUE(fs::file_size(dir / "p.svg") > 1000);
  const CliRun q = run("quality " + (dir / "m.msh").string() + " --domain " + data("cases/pentagon.geojson") + " --json");
  EXPECT_EQ(q.code, 0) << q.err;
  fs::remove_all(dir);
}

TEST(Cli, BadInputGivesExitTwoOneErrorLineAndNoFile) {
  const fs::path out = fs::temp_directory_path() / ("polysquare_cli_none_" + std::to_string(::getpid()) + ".msh");
  std::vector<std::string> files{bad("missing.geojson")};
  for (const auto& e : fs::directory_iterator(std::string(POLYSQUARE_TEST_DATA_DIR) + "/bad"))
    if (e.path().extension() == ".geojson") files.push_back(e.path().string());
  ASSERT_GE(files.size(), 20u);
  for (const std::string& f : files) {
    const auto t0 = std::chrono::steady_clock::now();
    const CliRun r = run("mesh " + f + " --size 1 -o " + out.string());
    // Refusals come from validation, before any meshing: well under a second even on a loaded machine.
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0) << f;
    EXPECT_EQ(r.code, 2) << f << ": " << r.err;
    EXPECT_EQ(r.err.rfind("error: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(fs::path(f).filename().string()), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
  }
  for (const std::string& size : {"0", "-2", "1e9"}) {
    const CliRun r = run("mesh " + data("cases/letter_I.geojson") + " --size " + size + " -o " + out.string());
    EXPECT_EQ(r.code, 2) << size << ": " << r.err;
    EXPECT_FALSE(fs::exists(out));
  }
  {  // too many quads: refused from an estimate before any work, with the limit in the message
    const CliRun r = run("mesh " + data("cases/letter_I.geojson") + " --size 0.001 --max-quads 100000 -o " + out.string());
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("--max-quads"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
  }
  const CliRun r = run("mesh " + data("cases/letter_I.geojson") + " --size 2 -o " + out.string() + ".stl");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_FALSE(fs::exists(out.string() + ".stl"));
}

TEST(Cli, InterruptLeavesNoPartialFile) {
  const fs::path dir = fs::temp_directory_path() / ("polysquare_cli_int_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path out = dir / "m.msh";
  // A run of a minute or more (2M quads), interrupted at several moments: every run must really be interrupted
  // (a run that finished first would test nothing), exit by the signal and leave no file and no temporary.
  for (const char* delay : {"0.3", "1.0", "2.0"}) {
    // Job control on (set -m): a non-interactive shell starts background jobs with SIGINT ignored, so on a busy
    // machine a signal sent before the program installs its handler was lost and the run finished.
    const std::string cmd = "set -m; " + std::string(POLYSQUARE_CLI) + " mesh " + data("cases/rect_feature.geojson") + " --size 0.1 -o " +
                            out.string() + " > /dev/null 2>&1 & pid=$!; sleep " + delay + "; kill -INT $pid; wait $pid; echo $? > " +
                            (dir / "rc").string();
    ASSERT_EQ(std::system(("bash -c '" + cmd + "'").c_str()), 0);
    std::ifstream rc(dir / "rc");
    int code = 0;
    rc >> code;
    EXPECT_EQ(code, 128 + SIGINT) << delay;
    EXPECT_FALSE(fs::exists(out)) << delay;
    for (const auto& e : fs::directory_iterator(dir)) EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos);
  }
  fs::remove_all(dir);
}

TEST(Cli, VersionPrintsTheProjectVersion) {
  const fs::path out = fs::temp_directory_path() / ("polysquare_cli_version_" + std::to_string(::getpid()));
  const int status = std::system((std::string(POLYSQUARE_CLI) + " --version > " + out.string()).c_str());
  std::ifstream in(out);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  fs::remove(out);
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_EQ(text.rfind("polysquare ", 0), 0u) << text;
  EXPECT_NE(text.find_first_of("0123456789"), std::string::npos) << text;
}

TEST(Cli, QualityReportsTrianglesAndRequireQuadsRefusesThem) {
  const fs::path dir = fs::temp_directory_path() / ("polysquare_cli_tri_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  // One quad and two triangles, as another tool's MSH 2.2 would hold them.
  std::ofstream(dir / "mixed.msh") << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n6\n1 0 0 0\n2 1 0 0\n3 1 1 0\n"
                                      "4 0 1 0\n5 2 0 0\n6 2 1 0\n$EndNodes\n$Elements\n3\n1 3 2 1 1 1 2 3 4\n"
                                      "2 2 2 1 1 2 5 6\n3 2 2 1 1 2 6 3\n$EndElements\n";
  const std::string mixed = (dir / "mixed.msh").string();
  const CliRun plain = run("quality " + mixed);
  EXPECT_EQ(plain.code, 0) << plain.err;
  EXPECT_NE(plain.err.find("warning: "), std::string::npos) << plain.err;
  EXPECT_NE(plain.err.find("2 triangles"), std::string::npos) << plain.err;
  const CliRun strict = run("quality " + mixed + " --require-quads");
  EXPECT_EQ(strict.code, 2) << strict.err;
  EXPECT_EQ(strict.err.rfind("error: ", 0), 0u) << strict.err;
  // A mesh of quads passes the same check.
  const CliRun made = run("mesh " + data("cases/letter_I.geojson") + " --size 2 -o " + (dir / "q.msh").string());
  ASSERT_EQ(made.code, 0) << made.err;
  const CliRun quads = run("quality " + (dir / "q.msh").string() + " --require-quads");
  EXPECT_EQ(quads.code, 0) << quads.err;
  EXPECT_EQ(quads.err, "");
  fs::remove_all(dir);
}

TEST(Cli, MshVersionAndFeatureOptions) {
  const fs::path dir = fs::temp_directory_path() / ("polysquare_cli_msh_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  auto header = [](const fs::path& p) {
    std::ifstream in(p);
    std::string line;
    std::getline(in, line);
    std::getline(in, line);
    return line;
  };
  // Physical groups named feature_* of dimension `dim` (0: point group, 1: curve) in $PhysicalNames.
  auto feature_groups = [](const fs::path& p, char dim) {
    std::ifstream in(p);
    std::string line;
    std::size_t n = 0;
    while (std::getline(in, line) && line != "$EndPhysicalNames")
      n += line.size() > 2 && line[0] == dim && line[1] == ' ' && line.find(" \"feature_") != std::string::npos;
    return n;
  };
  const std::string input = data("cases/square_feature.geojson") + " --size 3 -o ";
  ASSERT_EQ(run("mesh " + input + (dir / "default.msh").string()).code, 0);
  EXPECT_EQ(header(dir / "default.msh"), "2.2 0 8");
  EXPECT_EQ(feature_groups(dir / "default.msh", '0'), 1u);  // the feature curve's nodes as a point group
  EXPECT_EQ(feature_groups(dir / "default.msh", '1'), 0u);
  ASSERT_EQ(run("mesh " + input + (dir / "v41.msh").string() + " --msh-version 4.1 --msh-features lines").code, 0);
  EXPECT_EQ(header(dir / "v41.msh"), "4.1 0 8");
  EXPECT_EQ(feature_groups(dir / "v41.msh", '1'), 1u);
  EXPECT_EQ(feature_groups(dir / "v41.msh", '0'), 0u);
  ASSERT_EQ(run("mesh " + input + (dir / "none.msh").string() + " --msh-features none").code, 0);
  EXPECT_EQ(feature_groups(dir / "none.msh", '0') + feature_groups(dir / "none.msh", '1'), 0u);
  const CliRun bad = run("mesh " + input + (dir / "bad.msh").string() + " --msh-version 3");
  EXPECT_EQ(bad.code, 2) << bad.err;
  EXPECT_FALSE(fs::exists(dir / "bad.msh"));
  fs::remove_all(dir);
}

// Issue 52: lon/lat input is meshed in UTM metres, but every place the CLI prints after reading is in the
// file's own lon/lat: a part left out as smaller than one element (a 2 m square beside a square of about
// 0.2 km, meshed in a local frame moved next to the origin, and one of about 1 km, meshed where it is), the
// frame's origin, and a meshing error's places.
TEST(Cli, PlacesAfterReadingAreInTheLonLatOfTheInput) {
  const fs::path dir = fs::temp_directory_path() / ("polysquare_cli_lonlat_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  auto square = [](double lon, double lat, double side) {
    std::ostringstream os;
    os.precision(12);
    os << R"({"type":"Feature","properties":{},"geometry":{"type":"Polygon","coordinates":[[)" << "[" << lon << ","
       << lat << "],[" << lon + side << "," << lat << "],[" << lon + side << "," << lat + side << "],[" << lon << ","
       << lat + side << "],[" << lon << "," << lat << "]]]}}";
    return os.str();
  };
  // The place "(x, y)" after `after` in the text (NaN when none).
  auto place_after = [](const std::string& text, const std::string& after) {
    const std::size_t at = text.find(after);
    double x = NAN, y = NAN;
    if (at != std::string::npos) std::sscanf(text.c_str() + at + after.size(), " (%lf, %lf)", &x, &y);
    return std::pair{x, y};
  };
  for (const auto& [side, size] : {std::pair{0.002, "10"}, std::pair{0.01, "50"}}) {
    const double tiny_lon = -122.45 + 1.5 * side, tiny_lat = 37.75 + side / 2;  // the tiny square's corner
    const fs::path input = dir / "lonlat.geojson";
    std::ofstream(input) << R"({"type":"FeatureCollection","crs":{"type":"name","properties":{"name":"EPSG:4326"}},)"
                         << R"("features":[)" << square(-122.45, 37.75, side) << "," << square(tiny_lon, tiny_lat, side / 100)
                         << "]}";
    const CliRun r = run("mesh " + input.string() + " --size " + size + " -o " + (dir / "m.msh").string());
    ASSERT_EQ(r.code, 0) << r.err;
    const auto [lon, lat] = place_after(r.err, "is less than one element, at");
    EXPECT_NEAR(lon, tiny_lon + side / 200, side / 100) << r.err;  // the tiny square's centre, not UTM metres
    EXPECT_NEAR(lat, tiny_lat + side / 200, side / 100) << r.err;
    if (side == 0.002) {  // moved: the frame's origin is a place too
      const auto [olon, olat] = place_after(r.err, "meshed relative to");
      EXPECT_NEAR(olon, -122.45, 0.01) << r.err;
      EXPECT_NEAR(olat, 37.75, 0.01) << r.err;
      // An error from meshing (thrown on a worker thread, in the moved frame): its places in lon/lat as well.
      const CliRun e = run("mesh " + input.string() + " --size 10 --min-sj 0.9999999999 --max-poor-fraction 0 -o " +
                           (dir / "e.msh").string());
      ASSERT_EQ(e.code, 3) << e.err;
      const std::string error = e.err.substr(e.err.find("error:"));
      const auto [elon, elat] = place_after(error, " at");
      EXPECT_NEAR(elon, -122.45 + side / 2, side) << error;
      EXPECT_NEAR(elat, 37.75 + side / 2, side) << error;
      EXPECT_EQ(error.find("places relative to"), std::string::npos) << error;
    }
  }
  fs::remove_all(dir);
}
