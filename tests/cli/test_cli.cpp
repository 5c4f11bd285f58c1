// The command-line contract: exit codes, one "error:" line, no output file on failure.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <vector>
#include <cstdio>
#include <filesystem>
#include <fstream>
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
  // A run of a few seconds, interrupted at several moments (meshing, and possibly writing).
  for (const char* delay : {"0.3", "1.0", "2.0"}) {
    const std::string cmd = std::string(POLYSQUARE_CLI) + " mesh " + data("cases/rect_feature.geojson") + " --size 0.25 -o " +
                            out.string() + " > /dev/null 2>&1 & pid=$!; sleep " + delay + "; kill -INT $pid; wait $pid; echo $? > " +
                            (dir / "rc").string();
    ASSERT_EQ(std::system(("bash -c '" + cmd + "'").c_str()), 0);
    std::ifstream rc(dir / "rc");
    int code = 0;
    rc >> code;
    if (code == 0) {  // finished before the signal: the file must then be complete
      EXPECT_GT(fs::file_size(out), 1000u);
      fs::remove(out);
      continue;
    }
    EXPECT_EQ(code, 128 + SIGINT) << delay;
    EXPECT_FALSE(fs::exists(out)) << delay;
    for (const auto& e : fs::directory_iterator(dir)) EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos);
  }
  fs::remove_all(dir);
}
