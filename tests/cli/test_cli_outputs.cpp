// Issue 13, round two: outputs checked before meshing and committed together, option values validated, quality
// refusing meshes it cannot judge, refusals before any reading or meshing, messages that help
// (tests/data/adversarial/README.md; their time is measured by bench/adversarial_corpus.py).
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "polysquare/io/atomic_file.h"
#include "polysquare/io/mesh_io.h"
#include "polysquare/pipeline/check_options.h"
#include "polysquare/quality/quality.h"

namespace fs = std::filesystem;

namespace {
struct CliResult {
  int code;
  std::string out, err;
};
std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
CliResult run(const std::string& args) {
  const std::string tag = std::to_string(::getpid());
  const fs::path out = fs::temp_directory_path() / ("polysquare_cli_o_out_" + tag);
  const fs::path err = fs::temp_directory_path() / ("polysquare_cli_o_err_" + tag);
  const int status = std::system((std::string(POLYSQUARE_CLI) + " " + args + " > " + out.string() + " 2> " + err.string()).c_str());
  CliResult r{WEXITSTATUS(status), slurp(out), slurp(err)};
  fs::remove(out);
  fs::remove(err);
  return r;
}
std::string data(const std::string& rel) { return std::string(POLYSQUARE_DATA_DIR) + "/" + rel; }
std::string adversarial(const std::string& rel) { return std::string(POLYSQUARE_TEST_DATA_DIR) + "/adversarial/" + rel; }
std::size_t lines(const std::string& s) { return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n')); }

struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& name)
      : path(fs::temp_directory_path() / ("polysquare_" + name + "_" + std::to_string(::getpid()))) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  std::vector<std::string> entries() const {
    std::vector<std::string> e;
    for (const auto& x : fs::directory_iterator(path)) e.push_back(x.path().filename().string());
    std::sort(e.begin(), e.end());
    return e;
  }
};

// A case that takes seconds to mesh. Runs are not quiet: reading the input prints "region ... gives about N quads"
// on stderr, so a refusal that is the only line on stderr came before the input was read, let alone meshed.
const std::string kSlowInput = data("cases/rect_feature.geojson") + " --size 0.5";
}  // namespace

TEST(CliOutputs, EveryOutputIsRefusedBeforeMeshingAndNothingIsWritten) {
  TempDir dir("cli_outputs");
  const std::string d = dir.path.string();
  fs::copy_file(data("cases/letter_I.geojson"), dir.path / "in.json");
  const std::string input_before = slurp(dir.path / "in.json");
  const std::string long_name(300, 'n');
  struct Case {
    std::string args, fragment;
  };
  const std::vector<Case> cases{
      {kSlowInput + " -o " + d + "/m.msh --report " + d + "/missing/r.json", "does not exist (--report)"},
      {kSlowInput + " -o " + d + "/m.msh --picture " + d + "/missing/p.svg", "does not exist (--picture)"},
      {kSlowInput + " -o " + d + "/m.msh --partition-picture " + d + "/missing/p.svg", "does not exist (--partition-picture)"},
      {kSlowInput + " -o " + d + "/m.msh --report " + d + "/m.msh", "--report"},
      {kSlowInput + " -o " + d + "/m.msh --report " + d + "/r.json --picture " + d + "/r.json", "--picture"},
      {kSlowInput + " -o " + d + "/m.vtu --picture " + d + "/p.svg --partition-picture " + d + "/./p.svg",
       "names the same file as --picture"},
      {dir.path.string() + "/in.json --size 2 -o " + d + "/m.msh --report " + d + "/in.json", "overwrite the input"},
      {kSlowInput + " -o " + d, "is a directory"},
      {kSlowInput + " -o " + d + "/" + long_name + ".msh", "more than the file system allows"},
      {kSlowInput + " -o " + d + "/m.msh --report " + d + "/" + long_name + ".json", "more than the file system allows"},
  };
  for (const Case& c : cases) {
    const CliResult r = run("mesh " + c.args);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("error: ", 0), 0u) << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find(c.fragment), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"in.json"}) << c.args;
  }
  EXPECT_EQ(slurp(dir.path / "in.json"), input_before);
  // A .pvtu's first piece (or every piece asked for) in a directory's place.
  fs::create_directories(dir.path / "m_0.vtu");
  const CliResult r = run("mesh " + kSlowInput + " -o " + d + "/m.pvtu");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("m_0.vtu: is a directory"), std::string::npos) << r.err;
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"in.json", "m_0.vtu"}));
}

TEST(CliOutputs, LongOutputNamesAreWrittenWithShortTemporaries) {
  TempDir dir("cli_long");
  const std::string stem(245, 'a');  // 249 characters with ".msh": the old NAME.tmp.PID exceeded 255
  const fs::path out = dir.path / (stem + ".msh"), rep = dir.path / (std::string(240, 'r') + ".json");
  const CliResult r = run("mesh " + data("cases/letter_I.geojson") + " --size 2 -o " + out.string() + " --report " + rep.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_GT(fs::file_size(out), 1000u);
  EXPECT_GT(fs::file_size(rep), 100u);
  EXPECT_EQ(dir.entries().size(), 2u);
  EXPECT_LT(polysquare::temporary_path(out).filename().string().size(), 50u);
}

// Issue 52: --max-quads 2e9 with a size giving 1e9 quads (300 GB at kBytesPerQuad) is refused at once, naming the
// memory the mesh would need (it used to mesh until the machine killed it). A regression would grind for minutes:
// `timeout` ends it, and the bound on the time is generous (the refusal takes a fraction of a second).
TEST(CliOutputs, SizesBeyondTheAvailableMemoryAreRefusedAtOnce) {
  if (1e9 * polysquare::kBytesPerQuad <= polysquare::available_memory_bytes())
    GTEST_SKIP() << "this machine holds 1e9 quads";
  TempDir dir("cli_memory");
  const std::string d = dir.path.string();
  const fs::path err = dir.path.parent_path() / ("polysquare_cli_memory_err_" + std::to_string(::getpid()));
  const std::string cmd = "timeout 120 " + std::string(POLYSQUARE_CLI) + " mesh " + POLYSQUARE_TEST_DATA_DIR +
                          "/round3_outputs/big_square.geojson --size 0.0316 --max-quads 2e9 -o " + d +
                          "/m.msh --report " + d + "/r.json > /dev/null 2> " + err.string();
  const auto start = std::chrono::steady_clock::now();
  const int status = std::system(cmd.c_str());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const std::string text = slurp(err);
  fs::remove(err);
  EXPECT_EQ(WEXITSTATUS(status), 2) << text;
  EXPECT_LT(seconds, 10.0);
  EXPECT_EQ(lines(text), 1u) << text;  // the refusal alone, before the "region ... gives about N quads" line
  EXPECT_EQ(text.rfind("error: ", 0), 0u) << text;
  EXPECT_NE(text.find("big_square.geojson: --size 0.0316 would need about 1.00144e+09 quads"), std::string::npos) << text;
  EXPECT_NE(text.find("GB of memory"), std::string::npos) << text;
  EXPECT_NE(text.find("--max-quads"), std::string::npos) << text;
  EXPECT_TRUE(dir.entries().empty());
}

// Issue 52: a path longer than PATH_MAX (17 directory names of 250 letters), for -o or for --report, is refused
// before the input is read, naming the limit (not read as a missing directory, nor met by a writer after meshing).
TEST(CliOutputs, PathsLongerThanPathMaxAreRefusedBeforeReading) {
  TempDir dir("cli_path_max");
  std::string deep = dir.path.string();
  for (int k = 0; k < 17; ++k) deep += "/" + std::string(250, 'd');
  for (const std::string& outputs :
       {"-o " + deep + "/m.msh", "-o " + dir.path.string() + "/m.msh --report " + deep + "/r.json"}) {
    const CliResult r = run("mesh " + kSlowInput + " " + outputs);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("more than the system allows (PATH_MAX"), std::string::npos) << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;  // before reading: no "region ... gives about N quads" line
  }
  EXPECT_TRUE(dir.entries().empty());
}

// Issue 52: an output that is an input under another name (a symbolic link to the --boundary file, a hard link to
// the --features file) is refused before reading, naming both options, and the input stays as it was.
TEST(CliOutputs, OutputsThroughLinksToInputsAreRefused) {
  TempDir dir("cli_output_links");
  const fs::path boundary = dir.path / "lines.json", features = dir.path / "features.json";
  fs::copy_file(std::string(POLYSQUARE_TEST_DATA_DIR) + "/round3_outputs/boundary_lines.json", boundary);
  fs::copy_file(std::string(POLYSQUARE_TEST_DATA_DIR) + "/round3_outputs/feature_lines.json", features);
  fs::create_symlink(boundary, dir.path / "report.json");
  fs::create_hard_link(features, dir.path / "hard.json");
  const std::string lines_before = slurp(boundary), features_before = slurp(features);
  const std::string square = std::string(POLYSQUARE_TEST_DATA_DIR) + "/round3_outputs/square.geojson --size 10 -o " +
                             (dir.path / "m.msh").string();
  const std::vector<std::pair<std::string, std::string>> cases{
      {" --boundary " + boundary.string() + " --report " + (dir.path / "report.json").string(), "--boundary file"},
      {" --features " + features.string() + " --report " + (dir.path / "hard.json").string(), "--features file"}};
  for (const auto& [args, what] : cases) {
    const CliResult r = run("mesh " + square + args);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("--report would overwrite the " + what), std::string::npos) << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
  }
  EXPECT_EQ(slurp(boundary), lines_before);
  EXPECT_EQ(slurp(features), features_before);
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"features.json", "hard.json", "lines.json", "report.json"}));
}

// Issue 52: --size-picture is committed with the other outputs, all or none: its directory removed while the run
// meshes (after every check: -v says "stage simplify" once mesh_region started), the run ends in exit 2 and the mesh
// and report are not written either (the size picture used to be written after the others were committed).
TEST(CliOutputs, TheSizePictureIsCommittedWithTheOtherOutputs) {
  TempDir dir("cli_size_picture_batch");
  fs::create_directories(dir.path / "sub");
  const std::string d = dir.path.string(), err_file = fs::temp_directory_path() / ("polysquare_sp_err_" + std::to_string(::getpid()));
  const std::string cmd = std::string(POLYSQUARE_CLI) + " mesh " + std::string(POLYSQUARE_TEST_DATA_DIR) +
                          "/round3_outputs/big_square.geojson --size-min 2 --size-max 40 -v -o " + d + "/m.msh --report " +
                          d + "/r.json --size-picture " + d + "/sub/p.png 2> " + err_file +
                          " & pid=$!; n=0; until grep -q \"stage simplify\" " + err_file +
                          " || [ $n -gt 600 ]; do sleep 0.05; n=$((n+1)); done; rm -rf " + d + "/sub; wait $pid";
  const int status = std::system(("sh -c '" + cmd + "'").c_str());
  const std::string err = slurp(err_file);
  fs::remove(err_file);
  EXPECT_EQ(WEXITSTATUS(status), 2) << err;
  EXPECT_NE(err.find("error: " + d + "/sub/p.png"), std::string::npos) << err;
  EXPECT_EQ(err.find("error: "), err.rfind("error: ")) << err;  // one error line (-v prints the stages too)
  EXPECT_TRUE(dir.entries().empty());  // no mesh, no report, no temporary
}

TEST(CliOutputs, ARerunRemovesTheTemporariesOfAKilledRun) {
  TempDir dir("cli_stale");
  const fs::path out = dir.path / "m.msh";
  // The temporary a killed process would have left: same name scheme, the process id of one that has ended.
  const pid_t dead = ::fork();
  if (dead == 0) ::_exit(0);
  ASSERT_GT(dead, 0);
  ::waitpid(dead, nullptr, 0);
  const std::string mine = polysquare::temporary_path(out).filename().string();
  const std::string pid = std::to_string(::getpid());
  const std::string stale = mine.substr(0, mine.size() - pid.size() - 4) + std::to_string(dead) + ".tmp";
  const std::string alive = mine;  // this test process is alive: its temporary is not the rerun's to remove
  std::ofstream(dir.path / stale) << "partial";
  std::ofstream(dir.path / alive) << "in flight";
  const CliResult r = run("mesh " + data("cases/letter_I.geojson") + " --size 2 -o " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_FALSE(fs::exists(dir.path / stale));
  EXPECT_TRUE(fs::exists(dir.path / alive));
  EXPECT_TRUE(fs::exists(out));
}

TEST(CliOutputs, OptionValuesAreValidatedBeforeReading) {
  TempDir dir("cli_options");
  const std::string out = (dir.path / "m.msh").string();
  const std::vector<std::pair<std::string, std::string>> bad{
      {"--min-sj nan", "--min-sj"},          {"--min-sj -0.1", "--min-sj"},
      {"--min-sj 1.5", "--min-sj"},          {"--max-edge-ratio nan", "--max-edge-ratio"},
      {"--max-edge-ratio 0", "--max-edge-ratio"}, {"--max-edge-ratio -3", "--max-edge-ratio"},
      {"--max-poor-fraction nan", "--max-poor-fraction"}, {"--max-poor-fraction 2", "--max-poor-fraction"},
      {"--corner-angle nan", "--corner-angle"}, {"--corner-angle -5", "--corner-angle"},
      {"--simplify nan", "--simplify"},       {"--simplify -1", "--simplify"},
      {"--boundary-weight nan", "--boundary-weight"}, {"--boundary-weight -1", "--boundary-weight"},
      {"--feature-weight nan", "--feature-weight"}, {"--feature-weight -1", "--feature-weight"},
      {"--flat-corner-angle nan", "--flat-corner-angle"}, {"--flat-corner-angle 200", "--flat-corner-angle"},
      {"--feature-tolerance nan", "--feature-tolerance"}, {"--feature-tolerance -1", "--feature-tolerance"},
      {"--agree-turns nan", "--agree-turns"}, {"--agree-turns -1", "--agree-turns"},
      {"--max-quads -5", "--max-quads"},     {"--max-quads nan", "--max-quads"},
      {"--threads 1000000000", "--threads"}, {"--size nan", "--size"},
      {"--depth nan", "--depth"},            {"--pieces 3", "--pieces"},  // pieces need a .pvtu output
  };
  for (const auto& [opt, flag] : bad) {
    // --size is given first; a repeated --size is the last one CLI11 keeps.
    const CliResult r = run("mesh " + kSlowInput + " " + opt + " -o " + out);
    EXPECT_EQ(r.code, 2) << opt << ": " << r.err;
    EXPECT_EQ(r.err.rfind("error: ", 0), 0u) << opt << ": " << r.err;
    EXPECT_EQ(lines(r.err), 1u) << opt << ": " << r.err;  // nothing read before the refusal
    EXPECT_NE(r.err.find(flag), std::string::npos) << opt << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << opt;
  }
  // A directory as input is an input error, not an unexpected one.
  const CliResult r = run("mesh " + dir.path.string() + " --size 1 -o " + out);
  EXPECT_EQ(r.code, 2) << r.err;
  fs::create_directories(dir.path / "d.geojson");
  const CliResult g = run("mesh " + (dir.path / "d.geojson").string() + " --size 1 -o " + out);
  EXPECT_EQ(g.code, 2) << g.err;
  EXPECT_NE(g.err.find("is a directory"), std::string::npos) << g.err;
}

TEST(CliOutputs, QualityRefusesMeshesItCannotJudge) {
  for (const char* f : {"quality_nan.msh", "quality_inf.msh", "quality_no_cells.vtu", "quality_hexahedra.vtu",
                        "quality_triangles_only.msh"}) {
    const CliResult r = run("quality " + adversarial(f));
    EXPECT_EQ(r.code, 2) << f << ": " << r.err << r.out;
    EXPECT_EQ(r.err.rfind("error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(f), std::string::npos) << r.err;
    EXPECT_EQ(r.out.find("scaled Jacobian"), std::string::npos) << f << ": figures printed for a mesh not judged";
  }
}

// How fast (5 s bound; 42-59 s before the box intersection): bench/adversarial_corpus.py, not a test assertion.
TEST(CliOutputs, CombsAreRefusedWithTheirCrossing) {
  for (const char* f : {"comb_30000_crossing.geojson", "comb_30000_crossing_rotated.geojson"}) {
    const CliResult r = run("mesh " + adversarial(f) + " --size 1 -o /tmp/polysquare_comb_never.msh");
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("intersects itself at ("), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists("/tmp/polysquare_comb_never.msh"));
  }
  const CliResult r = run("mesh " + adversarial("comb_30000_feature_outside.geojson") + " --size 1 -o /tmp/polysquare_comb_never.msh");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("lies outside the domain, at (-5, 60001.5)"), std::string::npos) << r.err;
}

TEST(CliOutputs, MessagesNameThingsPlainly) {
  TempDir dir("cli_messages");
  const std::string out = (dir.path / "m.msh").string();
  {
    const CliResult r = run("mesh " + adversarial("multipolygon_not_array.geojson") + " --size 1 -o " + out);
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err.find("got MultiPolygon"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("MultiPolygon's coordinates must be an array"), std::string::npos) << r.err;
  }
  {  // a size far too small for the limit: the estimate is a plain number, not a wrapped integer
    const CliResult r = run("mesh " + data("cases/letter_I.geojson") + " --size 1e-150 -o " + out);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("--max-quads"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("-9223372036854775808"), std::string::npos) << r.err;
    EXPECT_LT(r.err.size(), 300u) << r.err;
  }
  {  // 50 feature points dropped by --repair: five named, then one line with the count
    std::ofstream f(dir.path / "points.geojson");
    f << R"({"type":"FeatureCollection","features":[{"type":"Feature","properties":{"role":"domain"},"geometry":)"
      << R"({"type":"Polygon","coordinates":[[[0,0],[20,0],[20,20],[0,20],[0,0]]]}})";
    for (int k = 0; k < 50; ++k)
      f << R"(,{"type":"Feature","properties":{"role":"feature"},"geometry":{"type":"Point","coordinates":[)" << 30 + k
        << ",5]}}";
    f << "]}";
    f.close();
    const CliResult r = run("mesh " + (dir.path / "points.geojson").string() + " --size 2 --repair -o " + out);
    EXPECT_EQ(r.code, 0) << r.err;
    std::size_t repaired = 0;
    for (std::size_t at = r.err.find("warning: repaired: "); at != std::string::npos; at = r.err.find("warning: repaired: ", at + 1))
      ++repaired;
    EXPECT_EQ(repaired, 5u) << r.err;
    EXPECT_NE(r.err.find("feature point (30, 5) lies outside the domain: dropped"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("... and 45 more repairs"), std::string::npos) << r.err;
  }
  {  // 1,000 dropped parts: a few lines and one summary, not 1,000 warnings
    const CliResult r = run("mesh " + adversarial("dropped_1000_parts.geojson") + " --size 2 -o " + out);
    EXPECT_EQ(r.code, 0) << r.err;
    std::size_t warnings = 0;
    for (std::size_t at = r.err.find("warning: "); at != std::string::npos; at = r.err.find("warning: ", at + 1)) ++warnings;
    EXPECT_LE(warnings, 5u) << r.err;
    EXPECT_NE(r.err.find("1000 parts smaller than one element"), std::string::npos) << r.err;
  }
}

TEST(CliOutputs, HoleInAHoleIsMeshedAsAnIsland) {
  TempDir dir("cli_island");
  const fs::path out = dir.path / "m.msh", rep = dir.path / "r.json";
  const CliResult r = run("mesh " + adversarial("hole_in_hole.geojson") + " --size 2 -o " + out.string() + " --report " + rep.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("meshed as an island"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("non-contiguous"), std::string::npos) << r.err;
  // 100 x 100 less the 60 x 60 lake plus the 20 x 20 island: 6,800 (the lake was meshed as land: 10,000).
  const polysquare::QuadMesh mesh = polysquare::read_mesh(out);
  EXPECT_NEAR(polysquare::mesh_area(mesh), 6800.0, 1e-6);
  EXPECT_EQ(r.err.find("area differs"), std::string::npos) << r.err;
}

TEST(CliOutputs, FarFromTheOriginIsMeshedInALocalFrame) {
  TempDir dir("cli_far");
  const fs::path out = dir.path / "m.msh";
  const CliResult r = run("mesh " + adversarial("far_smile_1e11.geojson") + " --size 2.5 -o " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("meshed relative to (1e+11, 1e+11)"), std::string::npos) << r.err;
  polysquare::QuadMesh mesh = polysquare::read_mesh(out);
  // Written back in the input's coordinates: smile spans [-50, 50]^2 around (1e11, 1e11).
  for (const auto& p : mesh.nodes) {
    ASSERT_GE(p.x, 1e11 - 50.001);
    ASSERT_LE(p.x, 1e11 + 50.001);
    ASSERT_GE(p.y, 1e11 - 50.001);
    ASSERT_LE(p.y, 1e11 + 50.001);
  }
  for (auto& p : mesh.nodes) p = {p.x - 1e11, p.y - 1e11};  // judged next to the origin, where digits suffice
  const polysquare::QualityReport q = polysquare::compute_quality(mesh);
  EXPECT_EQ(q.inverted, 0u);
  EXPECT_GT(q.sj.min, 0.2);
  EXPECT_GT(q.quads, 500u);
}

TEST(OutputBatchTest, AllOutputsOrNone) {
  TempDir dir("batch");
  const fs::path a = dir.path / "a.msh", b = dir.path / "b.json";
  std::ofstream(a) << "old a";
  {  // the second writer fails: the first output is not replaced, nothing new appears, no temporary is left
    polysquare::OutputBatch batch;
    polysquare::write_file_atomically(a, [](std::ostream& os) { os << "new a"; }, false);
    EXPECT_EQ(slurp(a), "old a");  // staged, not yet renamed
    EXPECT_THROW(polysquare::write_file_atomically(b, [](std::ostream& os) { os << "partial"; throw std::runtime_error("boom"); }, false),
                 std::runtime_error);
  }
  EXPECT_EQ(slurp(a), "old a");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"a.msh"});
  {  // both written: both replaced at commit
    polysquare::OutputBatch batch;
    polysquare::write_file_atomically(a, [](std::ostream& os) { os << "new a"; }, false);
    polysquare::write_file_atomically(b, [](std::ostream& os) { os << "new b"; }, false);
    EXPECT_EQ(dir.entries().size(), 3u);  // a.msh and two temporaries
    batch.commit();
  }
  EXPECT_EQ(slurp(a), "new a");
  EXPECT_EQ(slurp(b), "new b");
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"a.msh", "b.json"}));
}
