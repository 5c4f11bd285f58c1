// Issue 13, round two, and issue 52, round three (tests/data/round3_gis: GIS files, CRSs, rasters; arguments may
// name files of the corpus as {corpus}/FILE): the CLI on every row of tests/data/adversarial/cases.tsv ends as the row promises: exit 0
// with a mesh that passes the overlap-aware invariant check, or exit 2/3 with exactly one "error: " line naming
// what is wrong, and no file left behind (no output, no temporary, the input untouched). The rows are data; speed
// is measured by bench/adversarial_corpus.py, not here.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "polysquare/io/mesh_io.h"
#include "polysquare/pipeline/invariants.h"

namespace fs = std::filesystem;

namespace {

const fs::path kData = fs::path(POLYSQUARE_TEST_DATA_DIR);
// Round two's corpus and round three's (issue 52) of GIS files, CRSs and rasters: the same row format and promises.
const char* const kCorpora[] = {"adversarial", "round3_gis"};

/// One row of cases.tsv: name, file, command, arguments, exit code, fragments (see the file's header).
struct CorpusCase {
  std::string corpus;  // the directory under tests/data the row's files are in
  std::string name, file, command, args;
  int exit = 0;
  std::vector<std::string> fragments;
};

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : s) {
    if (c == sep) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

std::vector<CorpusCase> load_cases() {
  std::vector<CorpusCase> cases;
  for (const char* corpus : kCorpora) {
    std::ifstream in(kData / corpus / "cases.tsv");
    std::string line;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      const std::vector<std::string> col = split(line, '\t');
      if (col.size() != 6) throw std::runtime_error("cases.tsv: a row needs 6 tab-separated columns: " + line);
      CorpusCase c{corpus, col[0], col[1], col[2], col[3], std::stoi(col[4]), {}};
      if (!col[5].empty()) c.fragments = split(col[5], '|');
      cases.push_back(c);
    }
  }
  return cases;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) s.replace(at, from.size(), to);
  return s;
}

std::set<std::string> entries(const fs::path& dir) {
  std::set<std::string> e;
  for (const auto& x : fs::directory_iterator(dir)) e.insert(x.path().filename().string());
  return e;
}

// gtest prints a parameter by its name (not its bytes) in test names and failures.
void PrintTo(const CorpusCase& c, std::ostream* os) { *os << c.name; }

class AdversarialCorpus : public ::testing::TestWithParam<CorpusCase> {};

}  // namespace

TEST_P(AdversarialCorpus, EndsAsPromised) {
  const CorpusCase& c = GetParam();
  const fs::path kCorpus = kData / c.corpus;
  const fs::path dir = fs::temp_directory_path() / ("polysquare_corpus_" + c.name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "work");
  struct Cleanup {  // removed however the test ends (an ASSERT returns early)
    fs::path p;
    ~Cleanup() { std::error_code ec; fs::remove_all(p, ec); }
  } cleanup{dir};
  const fs::path work = dir / "work";  // the case's own directory: outputs go here, nothing else may appear
  // The input: a corpus file, the scratch directory itself ({dir}), or a copy in it ({copy}) for rows that aim an
  // output at the input.
  std::string input;
  fs::path copy;
  if (c.file == "{dir}") {
    input = work.string();
  } else if (c.args.find("{copy}") != std::string::npos) {
    copy = work / fs::path(c.file).filename();
    fs::copy_file(kCorpus / c.file, copy);
    input = copy.string();
  } else {
    input = (kCorpus / c.file).string();
  }
  ASSERT_TRUE(c.file == "{dir}" || fs::is_regular_file(kCorpus / c.file)) << c.file;
  const std::string copy_before = copy.empty() ? std::string() : slurp(copy);
  const std::set<std::string> before = entries(work);
  std::string args = replace_all(replace_all(replace_all(c.args, "{dir}", work.string()), "{copy}", input), "{corpus}",
                                 kCorpus.string());
  // The mesh: -o's value when the row gives one, else out.msh in the row's directory.
  fs::path mesh = work / "out.msh";
  if (const std::size_t o = args.find("-o "); o != std::string::npos)
    mesh = args.substr(o + 3, args.find(' ', o + 3) == std::string::npos ? std::string::npos : args.find(' ', o + 3) - o - 3);
  else if (c.command == "mesh")
    args += " -o " + mesh.string();
  if (c.command == "mesh") args += " -q";  // warnings and errors only: a refusal is then its one line
  const fs::path out = dir / "stdout", err = dir / "stderr";
  const std::string cmd = std::string(POLYSQUARE_CLI) + " " + c.command + " " + input + " " + args + " > " + out.string() +
                          " 2> " + err.string();
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status)) << cmd;
  const int code = WEXITSTATUS(status);
  const std::string so = slurp(out), se = slurp(err);
  const std::string name = c.file == "{dir}" ? std::string("work") : fs::path(c.file).filename().string();
  EXPECT_EQ(code, c.exit) << cmd << "\n" << se;
  for (std::string f : c.fragments) {
    f = replace_all(f, "{name}", name);
    if (f[0] == '!')
      EXPECT_EQ(se.find(f.substr(1)), std::string::npos) << c.name << ": stderr must not say \"" << f.substr(1) << "\"\n" << se;
    else
      EXPECT_NE((c.exit == 0 ? so + se : se).find(f), std::string::npos) << c.name << ": \"" << f << "\" missing\n" << se;
  }
  if (c.exit == 0 && c.command == "mesh") {
    // The mesh and nothing else (no temporary) besides what was there.
    std::set<std::string> expected = before;
    expected.insert(mesh.filename().string());
    for (const auto& e : entries(work))
      if (!expected.count(e)) EXPECT_NE(c.args.find(e), std::string::npos) << c.name << ": unexpected file " << e;
    ASSERT_TRUE(fs::exists(mesh)) << c.name;
    polysquare::QuadMesh m = polysquare::read_mesh(mesh);
    EXPECT_GT(m.quads.size(), 0u) << c.name;
    if (m.boundary_edges.empty()) {
      // A VTU carries no boundary tags: its boundary is the edges of one quad (the tags' consistency is then
      // given; conformity, shape and overlap are still checked).
      std::map<std::pair<std::int32_t, std::int32_t>, int> count;
      for (const auto& q : m.quads)
        for (int k = 0; k < 4; ++k) ++count[std::minmax(q[k], q[(k + 1) % 4])];
      for (const auto& [e, n] : count)
        if (n == 1) m.boundary_edges.push_back({e.first, e.second});
    }
    const polysquare::InvariantReport inv = polysquare::check_invariants(m);
    EXPECT_TRUE(inv.ok()) << c.name << ": " << inv.first_problem;
    EXPECT_EQ(inv.overlapping_quad_pairs, 0u) << c.name;
  } else if (c.exit != 0) {
    // A refusal: one line, "error: ", and no file written, replaced or left half-written.
    EXPECT_EQ(se.rfind("error: ", 0), 0u) << c.name << ": " << se;
    EXPECT_EQ(std::count(se.begin(), se.end(), '\n'), 1) << c.name << ": " << se;
    EXPECT_EQ(entries(work), before) << c.name;
  }
  if (!copy.empty()) EXPECT_EQ(slurp(copy), copy_before) << c.name << ": the input was changed";
}

INSTANTIATE_TEST_SUITE_P(Corpus, AdversarialCorpus, ::testing::ValuesIn(load_cases()),
                         [](const ::testing::TestParamInfo<CorpusCase>& info) {
                           std::string n = info.param.name;
                           for (char& ch : n)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return n;
                         });

// Every file of the corpus is run by at least one row, and every row's file exists: a file added without a
// promise, or a promise whose file went away, fails here.
TEST(AdversarialCorpusTable, CoversEveryFile) {
  const std::vector<CorpusCase> cases = load_cases();
  std::set<std::string> used, names;
  for (const CorpusCase& c : cases) {
    used.insert(c.corpus + "/" + c.file);
    used.insert(c.corpus + "/" + fs::path(c.file).stem().string());  // a Shapefile's .shx, .dbf, .prj go with its .shp
    for (std::size_t at = c.args.find("{corpus}/"); at != std::string::npos; at = c.args.find("{corpus}/", at + 1))
      used.insert(c.corpus + "/" + c.args.substr(at + 9, c.args.find(' ', at) - at - 9));  // a raster named in the arguments
    EXPECT_TRUE(names.insert(c.name).second) << "two rows named " << c.name;
    EXPECT_TRUE(c.exit == 0 || c.exit == 2 || c.exit == 3) << c.name;
    EXPECT_TRUE(c.exit == 0 || !c.fragments.empty()) << c.name << ": a refusal row names what the message must say";
  }
  for (const std::string corpus : kCorpora) {
    std::size_t files = 0;
    for (const auto& e : fs::directory_iterator(kData / corpus)) {
      const std::string f = e.path().filename().string();
      if (f == "README.md" || f == "cases.tsv") continue;
      ++files;
      EXPECT_TRUE(used.count(corpus + "/" + f) || (f.find('.') != std::string::npos &&
                                                   used.count(corpus + "/" + fs::path(f).stem().string())))
          << corpus << "/" << f << " has no row in cases.tsv";
    }
    EXPECT_GE(files, corpus == "adversarial" ? 60u : 20u) << corpus;
  }
}
