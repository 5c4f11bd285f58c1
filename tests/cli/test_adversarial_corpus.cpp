// Issue 13, round two, and issue 52, round three: the CLI on every row of each corpus directory's cases.tsv
// (kCorpora) ends as the row promises: exit 0 with a mesh that passes the overlap-aware invariant check, or exit
// 2/3 with exactly one "error: " line naming what is wrong, and no file left behind (no output, no temporary, the
// input untouched). The rows are data; speed is measured by bench/adversarial_corpus.py, not here.
//
// Beyond {dir} and {copy}, a row's arguments may hold these directives (round three's outputs, faults and MPI):
//   {copy:FILE}  FILE of the corpus copied into the row's directory, replaced by the copy's path; it must be
//                unchanged after the run (an output aimed at a --boundary or --features file)
//   {mkdir:NAME} a directory NAME made in the row's directory before the run (where a companion file would go);
//                removed from the arguments
//   {expect:NAME} exit 0: the run must leave the file NAME in the row's directory (a companion: .ll, .pli);
//                removed from the arguments
//   {long:N}     N letters "n" (file names too long for the file system)
//   {vmem:MB}    the run under `ulimit -v` of MB megabytes (out of memory; skipped under ASan); removed from the
//                arguments
//   {np:N}       the run under `mpirun --quiet -np N` (skipped in a build without MPI; under ASan without the
//                ranks' leak check); removed from the arguments
//   {corpus}     the corpus directory (round3_gis: rasters named in the arguments, {corpus}/FILE)
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
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "polysquare/io/mesh_io.h"
#include "polysquare/pipeline/invariants.h"

namespace fs = std::filesystem;

namespace {

// Built under AddressSanitizer (scripts/sanitize): gcc says so with __SANITIZE_ADDRESS__, clang with __has_feature.
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kAddressSanitizer = true;
#else
constexpr bool kAddressSanitizer = false;
#endif
#else
constexpr bool kAddressSanitizer = false;
#endif

// The corpus directories under tests/data whose cases.tsv rows are run, each with its README.md listing every file
// (a new corpus: add its directory here; its test names are prefixed by it).
const std::vector<std::string> kCorpora{"adversarial", "round3_outputs", "round3_gis"};

fs::path corpus_dir(const std::string& corpus) { return fs::path(POLYSQUARE_TEST_DATA_DIR) / corpus; }

/// One row of a cases.tsv: name, file, command, arguments, exit code, fragments (see the file's header); the
/// corpus directory it belongs to.
struct CorpusCase {
  std::string corpus, name, file, command, args;
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

std::vector<CorpusCase> load_cases(const std::string& corpus) {
  std::vector<CorpusCase> cases;
  std::ifstream in(corpus_dir(corpus) / "cases.tsv");
  if (!in) throw std::runtime_error(corpus + "/cases.tsv: cannot be read");
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> col = split(line, '\t');
    if (col.size() != 6) throw std::runtime_error(corpus + "/cases.tsv: a row needs 6 tab-separated columns: " + line);
    CorpusCase c{corpus, col[0], col[1], col[2], col[3], std::stoi(col[4]), {}};
    if (!col[5].empty()) c.fragments = split(col[5], '|');
    cases.push_back(c);
  }
  return cases;
}

std::vector<CorpusCase> load_all_cases() {
  std::vector<CorpusCase> cases;
  for (const std::string& corpus : kCorpora) {
    const std::vector<CorpusCase> some = load_cases(corpus);
    cases.insert(cases.end(), some.begin(), some.end());
  }
  return cases;
}

// The directives of a row's arguments (see the top of this file), read and removed.
struct Directives {
  std::vector<std::string> copies, mkdirs, expects;
  std::string vmem_mb, processes;
};

std::string take_directives(std::string args, Directives& d) {
  const std::regex directive(R"(\{(copy|mkdir|expect|long|vmem|np):([^}]*)\})");
  std::string out;
  std::smatch m;
  while (std::regex_search(args, m, directive)) {
    out += m.prefix().str();
    const std::string kind = m[1].str(), value = m[2].str();
    if (kind == "copy") {
      d.copies.push_back(value);
      out += "{copy:" + value + "}";  // replaced by the copy's path once the directory is known
    } else if (kind == "mkdir") {
      d.mkdirs.push_back(value);
    } else if (kind == "expect") {
      d.expects.push_back(value);
    } else if (kind == "long") {
      out += std::string(static_cast<std::size_t>(std::stoul(value)), 'n');
    } else if (kind == "vmem") {
      d.vmem_mb = value;
    } else {
      d.processes = value;
    }
    args = m.suffix().str();
  }
  return out + args;
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
  const fs::path kCorpus = corpus_dir(c.corpus);
  Directives directives;
  const std::string row_args = take_directives(c.args, directives);
  if (!directives.processes.empty() && std::string(POLYSQUARE_MPIRUN).empty()) GTEST_SKIP() << "built without MPI";
  // AddressSanitizer reserves terabytes of address space for its shadow memory: under `ulimit -v` the CLI does not
  // even load (exit 127, "failed to map segment"), so an out-of-memory row says nothing there.
  if (!directives.vmem_mb.empty() && kAddressSanitizer) GTEST_SKIP() << "{vmem:} rows need a build without ASan";
  const fs::path dir = fs::temp_directory_path() / ("polysquare_corpus_" + c.corpus + "_" + c.name + "_" + std::to_string(::getpid()));
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
  } else if (row_args.find("{copy}") != std::string::npos) {
    copy = work / fs::path(c.file).filename();
    fs::copy_file(kCorpus / c.file, copy);
    input = copy.string();
  } else {
    input = (kCorpus / c.file).string();
  }
  ASSERT_TRUE(c.file == "{dir}" || fs::is_regular_file(kCorpus / c.file)) << c.file;
  const std::string copy_before = copy.empty() ? std::string() : slurp(copy);
  // {copy:FILE}: more files of the corpus in the row's directory, to stay untouched; {mkdir:NAME}: directories.
  std::map<fs::path, std::string> kept;
  std::string args = row_args;
  for (const std::string& f : directives.copies) {
    const fs::path to = work / fs::path(f).filename();
    if (!fs::exists(to)) fs::copy_file(kCorpus / f, to);
    kept[to] = slurp(to);
    args = replace_all(args, "{copy:" + f + "}", to.string());
  }
  for (const std::string& d : directives.mkdirs) fs::create_directories(work / d);
  const std::set<std::string> before = entries(work);
  args = replace_all(replace_all(replace_all(args, "{dir}", work.string()), "{copy}", input), "{corpus}",
                     kCorpus.string());
  // The mesh: -o's value when the row gives one, else out.msh in the row's directory.
  fs::path mesh = work / "out.msh";
  if (const std::size_t o = args.find("-o "); o != std::string::npos)
    mesh = args.substr(o + 3, args.find(' ', o + 3) == std::string::npos ? std::string::npos : args.find(' ', o + 3) - o - 3);
  else if (c.command == "mesh")
    args += " -o " + mesh.string();
  if (c.command == "mesh") args += " -q";  // warnings and errors only: a refusal is then its one line
  const fs::path out = dir / "stdout", err = dir / "stderr";
  std::string cmd = std::string(POLYSQUARE_CLI) + " " + c.command + " " + input + " " + args;
  if (!directives.processes.empty())
    cmd = std::string(POLYSQUARE_MPIRUN) + " --quiet --allow-run-as-root --oversubscribe -np " + directives.processes +
          " " + cmd;
  // Under ASan the ranks' leak check is off (memory errors are still caught): Open MPI leaks at MPI_Finalize, most
  // of it from components it has unloaded by then, whose frames LeakSanitizer shows as "<unknown module>", which
  // no suppression can name.
  if (!directives.processes.empty() && kAddressSanitizer)
    cmd = "ASAN_OPTIONS=\"${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0\" " + cmd;
  cmd += " > " + out.string() + " 2> " + err.string();
  if (!directives.vmem_mb.empty())
    cmd = "ulimit -v " + std::to_string(std::stoul(directives.vmem_mb) * 1024) + " && " + cmd;
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
    for (const std::string& e : directives.expects) {
      expected.insert(e);
      EXPECT_TRUE(fs::is_regular_file(work / e) && fs::file_size(work / e) > 0) << c.name << ": " << e << " missing";
    }
    for (const auto& e : entries(work))
      if (!expected.count(e)) EXPECT_NE(args.find(e), std::string::npos) << c.name << ": unexpected file " << e;
    ASSERT_TRUE(fs::exists(mesh)) << c.name;
    // The solver formats (.gr3, .nc, ...) are not read back here: their writers take the mesh that passed the
    // pipeline's own invariant check, and tests/io read them; these rows are about the files beside them.
    const std::string ext = mesh.extension().string();
    if (ext != ".msh" && ext != ".vtu" && ext != ".pvtu") {
      EXPECT_GT(fs::file_size(mesh), 0u) << c.name;
      return;
    }
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
  for (const auto& [path, bytes] : kept) EXPECT_EQ(slurp(path), bytes) << c.name << ": " << path << " was changed";
}

// Test names: the row's name, prefixed by its corpus but for round two's (whose names stay as they were).
INSTANTIATE_TEST_SUITE_P(Corpus, AdversarialCorpus, ::testing::ValuesIn(load_all_cases()),
                         [](const ::testing::TestParamInfo<CorpusCase>& info) {
                           std::string n = (info.param.corpus == "adversarial" ? "" : info.param.corpus + "_") +
                                           info.param.name;
                           for (char& ch : n)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return n;
                         });

// Every file of each corpus is run by at least one row (and listed in its README.md), and every row's file
// exists: a file added without a promise, or a promise whose file went away, fails here.
TEST(AdversarialCorpusTable, CoversEveryFile) {
  const std::map<std::string, std::size_t> least_files{{"adversarial", 60}, {"round3_outputs", 15}, {"round3_gis", 20}};
  for (const std::string& corpus : kCorpora) {
    const std::vector<CorpusCase> cases = load_cases(corpus);
    std::set<std::string> used, names;
    for (const CorpusCase& c : cases) {
      used.insert(c.file);
      used.insert(fs::path(c.file).stem().string());  // a Shapefile's .shx, .dbf, .prj go with its .shp
      for (std::size_t at = c.args.find("{corpus}/"); at != std::string::npos; at = c.args.find("{corpus}/", at + 1))
        used.insert(c.args.substr(at + 9, c.args.find(' ', at) - at - 9));  // a raster named in the arguments
      Directives d;
      take_directives(c.args, d);
      used.insert(d.copies.begin(), d.copies.end());
      EXPECT_TRUE(names.insert(c.name).second) << corpus << ": two rows named " << c.name;
      EXPECT_TRUE(c.exit == 0 || c.exit == 2 || c.exit == 3) << corpus << ": " << c.name;
      EXPECT_TRUE(c.exit == 0 || !c.fragments.empty())
          << corpus << ": " << c.name << ": a refusal row names what the message must say";
      EXPECT_TRUE(c.file == "{dir}" || fs::is_regular_file(corpus_dir(corpus) / c.file)) << corpus << ": " << c.file;
    }
    const std::string readme = slurp(corpus_dir(corpus) / "README.md");
    std::size_t files = 0;
    for (const auto& e : fs::directory_iterator(corpus_dir(corpus))) {
      const std::string f = e.path().filename().string();
      if (f == "README.md" || f == "cases.tsv") continue;
      ++files;
      EXPECT_TRUE(used.count(f) || (f.find('.') != std::string::npos && used.count(fs::path(f).stem().string())))
          << corpus << ": " << f << " has no row in cases.tsv";
      EXPECT_NE(readme.find(fs::path(f).stem().string()), std::string::npos) << corpus << ": " << f << " is not in README.md";
    }
    const auto least = least_files.find(corpus);
    EXPECT_GE(files, least == least_files.end() ? 1u : least->second) << corpus;
  }
}
