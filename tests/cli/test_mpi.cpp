// `mpirun -np P polysquare mesh ...` (driver/mpi_driver.h): the same mesh, byte for byte, on any number of
// processes, on a small case and on a coast whose failed subregions are repaired; errors end every process.
// Skipped when the build has no MPI (POLYSQUARE_MPIRUN empty).
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

namespace fs = std::filesystem;

namespace {

struct MpiRun {
  int code;
  std::string err;
};

// processes 0: the plain command, no mpirun.
MpiRun mesh(int processes, const std::string& args, const fs::path& dir) {
  const fs::path err = dir / ("err_" + std::to_string(processes));
  std::string cmd = std::string(POLYSQUARE_CLI) + " mesh " + args;
  if (processes > 0)
    cmd = std::string(POLYSQUARE_MPIRUN) + " --allow-run-as-root --oversubscribe -np " + std::to_string(processes) + " " + cmd;
  const int status = std::system((cmd + " > /dev/null 2> " + err.string()).c_str());
  std::ifstream in(err);
  return {WEXITSTATUS(status), std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>())};
}

std::string bytes(const fs::path& f) {
  std::ifstream in(f, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::string data(const std::string& rel) { return std::string(POLYSQUARE_DATA_DIR) + "/" + rel; }

fs::path scratch(const char* name) {
  const fs::path dir = fs::temp_directory_path() / (std::string("polysquare_mpi_") + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

}  // namespace

TEST(Mpi, SmallCaseIsByteIdenticalOnOneTwoAndThreeProcesses) {
  if (std::string(POLYSQUARE_MPIRUN).empty()) GTEST_SKIP() << "built without MPI";
  const fs::path dir = scratch("small");
  // smile: one part, seven candidates (divided among the processes), two subregions.
  const std::string in = data("cases/smile.geojson") + " --size 2.5 -o ";
  ASSERT_EQ(mesh(0, in + (dir / "p0.msh").string(), dir).code, 0);
  const std::string one = bytes(dir / "p0.msh");
  ASSERT_GT(one.size(), 10000u);
  for (int p : {1, 2, 3}) {
    const fs::path out = dir / ("p" + std::to_string(p) + ".msh");
    const MpiRun r = mesh(p, in + out.string() + " --report " + (dir / "r.json").string(), dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(bytes(out) == one) << p << " processes";
    if (p > 1) {
      std::ifstream rep(dir / "r.json");
      EXPECT_EQ(nlohmann::json::parse(rep)["summary"]["processes"], p);
    }
  }
  fs::remove_all(dir);
}

TEST(Mpi, CoastWithRepairedSubregionsIsByteIdenticalOnTwoAndThreeProcesses) {
  if (std::string(POLYSQUARE_MPIRUN).empty()) GTEST_SKIP() << "built without MPI";
  const fs::path dir = scratch("coast");
  // delta_water at 200 m: several parts (divided among the processes) and, in the largest, subregions whose
  // maps fail and are repaired by patches; at 2 processes the parts and subregions land on either.
  const std::string in = data("cases/delta_water.geojson") + " --size 200 -o ";
  ASSERT_EQ(mesh(0, in + (dir / "p0.msh").string() + " --report " + (dir / "r0.json").string(), dir).code, 0);
  std::ifstream rep0(dir / "r0.json");
  const auto summary = nlohmann::json::parse(rep0)["summary"];
  ASSERT_GE(summary["unstructured_subregions"].get<int>(), 1) << "the case must exercise a repair";
  const std::string one = bytes(dir / "p0.msh");
  for (int p : {2, 3}) {
    const fs::path out = dir / ("p" + std::to_string(p) + ".msh");
    const MpiRun r = mesh(p, in + out.string(), dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(bytes(out) == one) << p << " processes";
  }
  fs::remove_all(dir);
}

TEST(Mpi, SubregionsOfOnePartAreDividedAndTheirRepairsMatchOneProcess) {
  if (std::string(POLYSQUARE_MPIRUN).empty()) GTEST_SKIP() << "built without MPI";
  const fs::path dir = scratch("subregions");
  // delta_box at 200 m with --parts 64: one part, one candidate in the first round, so the processes divide
  // its subregions (maps, split tests, snaps, patches) and one of them solves the quantization; dozens of
  // subregions fail and are repaired by patches.
  const std::string in = data("cases/delta_box.geojson") + " --size 200 --parts 64 -o ";
  ASSERT_EQ(mesh(0, in + (dir / "p0.msh").string() + " --report " + (dir / "r0.json").string(), dir).code, 0);
  std::ifstream rep0(dir / "r0.json");
  ASSERT_GE(nlohmann::json::parse(rep0)["summary"]["unstructured_subregions"].get<int>(), 1);
  const MpiRun r = mesh(2, in + (dir / "p2.msh").string(), dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(bytes(dir / "p2.msh") == bytes(dir / "p0.msh"));
  fs::remove_all(dir);
}

TEST(Mpi, ErrorsEndEveryProcessWithTheirExitCodeAndNoFile) {
  if (std::string(POLYSQUARE_MPIRUN).empty()) GTEST_SKIP() << "built without MPI";
  const fs::path dir = scratch("errors");
  // Bad input: every process meets it; one error line (rank 0 speaks), exit 2.
  MpiRun r = mesh(2, data("cases/smile.geojson") + " --size -1 -o " + (dir / "a.msh").string(), dir);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(r.err.find("error: "), 0u) << r.err;
  EXPECT_EQ(r.err.find("error: ", 1), std::string::npos) << r.err;
  // A mesh that cannot be made at this size: exit 3 on every process, nothing written.
  r = mesh(2, data("cases/smile.geojson") + " --size 1000 -o " + (dir / "b.msh").string(), dir);
  EXPECT_NE(r.code, 0) << r.err;
  EXPECT_FALSE(fs::exists(dir / "a.msh"));
  EXPECT_FALSE(fs::exists(dir / "b.msh"));
  fs::remove_all(dir);
}

// A .pvtu on several processes: each writes its share of the pieces (k % processes == rank), and the files are
// those of one process, byte for byte. A piece one process cannot write stops all of them: nothing is written.
TEST(Mpi, PvtuPiecesAreWrittenByEachProcessAndMatchOneProcess) {
  if (std::string(POLYSQUARE_MPIRUN).empty()) GTEST_SKIP() << "built without MPI";
  const fs::path dir = scratch("pvtu");
  const std::string in = data("cases/smile.geojson") + " --size 2.5 --pieces 3 -o ";
  ASSERT_EQ(mesh(0, in + (dir / "one.pvtu").string(), dir).code, 0);
  const MpiRun two = mesh(2, in + (dir / "two.pvtu").string(), dir);
  ASSERT_EQ(two.code, 0) << two.err;
  for (int k = 0; k < 3; ++k) {
    const std::string a = bytes(dir / ("one_" + std::to_string(k) + ".vtu"));
    ASSERT_GT(a.size(), 1000u) << k;
    EXPECT_EQ(a, bytes(dir / ("two_" + std::to_string(k) + ".vtu"))) << "piece " << k;
  }
  std::string index = bytes(dir / "two.pvtu");
  for (std::size_t at; (at = index.find("two_")) != std::string::npos;) index.replace(at, 4, "one_");
  EXPECT_EQ(index, bytes(dir / "one.pvtu"));
  // Pieces asked for are checked before meshing, on every process alike.
  const fs::path fail = dir / "fail";
  fs::create_directories(fail / "m_1.vtu");
  const MpiRun early = mesh(2, in + (fail / "m.pvtu").string(), dir);
  EXPECT_EQ(early.code, 2) << early.err;
  EXPECT_NE(early.err.find("m_1.vtu: is a directory"), std::string::npos) << early.err;
  // Without --pieces their number follows the mesh (two here, one per process): as many as the processes (or the
  // estimate) will make are checked before meshing too (issue 52; piece 1, process 1's, used to be found only when
  // that process wrote it, after meshing). One line, nothing written.
  const MpiRun bad = mesh(2, data("cases/smile.geojson") + " --size 2.5 -o " + (fail / "m.pvtu").string() +
                                 " --report " + (fail / "r.json").string(), dir);
  EXPECT_EQ(bad.code, 2) << bad.err;
  EXPECT_NE(bad.err.find("m_1.vtu: is a directory"), std::string::npos) << bad.err;
  EXPECT_EQ(bad.err.find("error: ", 1), std::string::npos) << bad.err;
  for (const char* f : {"m.pvtu", "m_0.vtu", "r.json"}) EXPECT_FALSE(fs::exists(fail / f)) << f;
  fs::remove_all(dir);
}
