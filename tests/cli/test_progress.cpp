// Progress and verbosity: stage events from the library, a progress line on a terminal only, --verbose stage
// timings, --quiet.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>
#include <sys/wait.h>
#include <unistd.h>

#include "polysquare/input/read_region.h"
#include "polysquare/pipeline/mesh_region.h"

namespace fs = std::filesystem;
using namespace polysquare;

namespace {

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

struct Piped {
  int code;
  std::string out, err;
};

// Runs `shell` (a shell command line) with stdout and stderr into files: neither is a terminal.
Piped run_piped(const std::string& shell) {
  const fs::path base = fs::temp_directory_path() / ("polysquare_progress_" + std::to_string(::getpid()));
  const std::string cmd = shell + " > " + base.string() + ".out 2> " + base.string() + ".err";
  const int status = std::system(cmd.c_str());
  Piped r{WEXITSTATUS(status), read_text(base.string() + ".out"), read_text(base.string() + ".err")};
  fs::remove(base.string() + ".out");
  fs::remove(base.string() + ".err");
  return r;
}

std::string cli() { return POLYSQUARE_CLI; }
std::string case_path(const std::string& name) { return std::string(POLYSQUARE_DATA_DIR) + "/cases/" + name + ".geojson"; }

class Progress : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("polysquare_progress_dir_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string mesh_cmd(const std::string& name, const std::string& size) const {
    return cli() + " mesh " + case_path(name) + " --size " + size + " -o " + (dir_ / "m.msh").string();
  }
  fs::path dir_;
};

}  // namespace

TEST(ProgressEvents, MeshRegionReportsEveryStageAndEveryPartWithoutChangingTheMesh) {
  // Two polygon parts, so "mesh parts" advances twice.
  Region region;
  region.rings.push_back({{{0, 0}, {10, 0}, {10, 10}, {0, 10}}, 0, false});
  region.rings.push_back({{{20, 0}, {32, 0}, {32, 8}, {20, 8}}, 1, false});
  region.num_parts = 2;
  validate_region(region);
  MeshOptions options;
  options.size.h = 1.0;
  options.run.threads = 2;
  std::vector<ProgressEvent> events;
  options.run.progress = [&](const ProgressEvent& e) { events.push_back(e); };
  const MeshResult with = mesh_region(region, options);
  options.run.progress = nullptr;
  const MeshResult without = mesh_region(region, options);
  EXPECT_EQ(with.mesh.nodes, without.mesh.nodes);
  EXPECT_EQ(with.mesh.quads, without.mesh.quads);

  std::vector<std::string> seen;
  std::vector<std::size_t> advanced;
  for (const ProgressEvent& e : events) {
    if (e.kind == ProgressEvent::Kind::advanced) {
      EXPECT_EQ(e.stage, "mesh parts");
      EXPECT_EQ(e.total, 2u);
      advanced.push_back(e.done);
      continue;
    }
    seen.push_back((e.kind == ProgressEvent::Kind::started ? "+" : "-") + e.stage);
    if (e.kind == ProgressEvent::Kind::finished) EXPECT_GE(e.seconds, 0.0);
  }
  const std::vector<std::string> expected{"+simplify", "-simplify", "+mesh parts", "-mesh parts", "+assemble", "-assemble"};
  EXPECT_EQ(seen, expected);
  EXPECT_EQ(advanced, (std::vector<std::size_t>{1, 2}));
  // The parts are announced between the start and the end of their stage.
  std::size_t first_advance = 0, mesh_parts_end = 0;
  for (std::size_t i = 0; i < events.size(); ++i) {
    if (events[i].kind == ProgressEvent::Kind::advanced && first_advance == 0) first_advance = i;
    if (events[i].kind == ProgressEvent::Kind::finished && events[i].stage == "mesh parts") mesh_parts_end = i;
  }
  EXPECT_EQ(first_advance, 3u);
  EXPECT_EQ(mesh_parts_end, 5u);
}

TEST_F(Progress, PipeGetsNoProgressLineAndVerboseGetsStageTimings) {
  const Piped plain = run_piped("env -u CI " + mesh_cmd("letter_I", "2"));
  ASSERT_EQ(plain.code, 0) << plain.err;
  EXPECT_EQ(plain.err.find('\r'), std::string::npos) << plain.err;
  EXPECT_EQ(plain.err.find("\033["), std::string::npos) << plain.err;
  EXPECT_EQ(plain.err.find("mesh parts"), std::string::npos) << plain.err;
  EXPECT_EQ(plain.err.find("stage "), std::string::npos) << plain.err;
  EXPECT_NE(plain.out.find("quads"), std::string::npos) << plain.out;

  const Piped verbose = run_piped("env -u CI " + mesh_cmd("letter_I", "2") + " --verbose");
  ASSERT_EQ(verbose.code, 0) << verbose.err;
  EXPECT_EQ(verbose.err.find('\r'), std::string::npos) << verbose.err;
  // Every stage, in order, each on its own line with its seconds.
  std::size_t at = 0;
  for (const char* stage : {"read input", "simplify", "mesh parts", "assemble", "quality", "write"}) {
    const std::size_t found = verbose.err.find(std::string("stage ") + stage, at);
    ASSERT_NE(found, std::string::npos) << stage << " in\n" << verbose.err;
    const std::size_t eol = verbose.err.find('\n', found);
    const std::string line = verbose.err.substr(found, eol - found);
    EXPECT_NE(line.find(" s"), std::string::npos) << line;
    EXPECT_NE(line.find_first_of("0123456789"), std::string::npos) << line;
    at = found;
  }
  // Apart from the timings, the same messages as without --verbose.
  std::string rest;
  std::size_t pos = 0;
  while (pos < verbose.err.size()) {
    const std::size_t eol = verbose.err.find('\n', pos);
    const std::string line = verbose.err.substr(pos, eol == std::string::npos ? std::string::npos : eol - pos + 1);
    if (line.rfind("stage ", 0) != 0) rest += line;
    pos = eol == std::string::npos ? verbose.err.size() : eol + 1;
  }
  EXPECT_EQ(rest, plain.err);
}

TEST_F(Progress, QuietPrintsNothingForACleanRun) {
  const Piped quiet = run_piped("env -u CI " + mesh_cmd("letter_I", "2") + " --quiet");
  ASSERT_EQ(quiet.code, 0) << quiet.err;
  EXPECT_EQ(quiet.out, "");
  EXPECT_EQ(quiet.err, "");
  EXPECT_GT(fs::file_size(dir_ / "m.msh"), 1000u);
  // Errors still show.
  const Piped bad = run_piped(cli() + " mesh " + case_path("letter_I") + " --size -1 --quiet -o " + (dir_ / "x.msh").string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_EQ(bad.err.rfind("error: ", 0), 0u) << bad.err;
}

TEST_F(Progress, TerminalShowsAProgressLineUnlessCiIsSet) {
  if (std::system("command -v script > /dev/null 2>&1") != 0) GTEST_SKIP() << "script (util-linux) not installed";
  // script runs the command on a pseudo-terminal and copies what it printed there to its own stdout.
  const std::string inner = mesh_cmd("letter_I", "2");
  const Piped tty = run_piped("env -u CI TERM=xterm script -q -e -c '" + inner + "' /dev/null");
  ASSERT_EQ(tty.code, 0) << tty.out << tty.err;
  EXPECT_NE(tty.out.find("\033[Kpolysquare: mesh parts 1/1 ... "), std::string::npos) << tty.out;
  EXPECT_NE(tty.out.find("\r\033[K"), std::string::npos) << tty.out;  // the line is erased again
  // Nothing of the line is left after its last erase: only the normal messages follow.
  const std::size_t last_erase = tty.out.rfind("\r\033[K");
  EXPECT_EQ(tty.out.find("... ", last_erase), std::string::npos) << tty.out.substr(last_erase);

  const Piped ci = run_piped("env CI=true TERM=xterm script -q -e -c '" + inner + "' /dev/null");
  ASSERT_EQ(ci.code, 0) << ci.out << ci.err;
  EXPECT_EQ(ci.out.find("polysquare: mesh parts"), std::string::npos) << ci.out;
  EXPECT_EQ(ci.out.find("\033[K"), std::string::npos) << ci.out;

  const Piped quiet = run_piped("env -u CI TERM=xterm script -q -e -c '" + inner + " --quiet' /dev/null");
  ASSERT_EQ(quiet.code, 0) << quiet.out << quiet.err;
  EXPECT_EQ(quiet.out.find("mesh parts"), std::string::npos) << quiet.out;
}
