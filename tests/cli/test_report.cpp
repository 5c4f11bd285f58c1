// The report `polysquare mesh --report` writes: it follows schema/report.schema.json, the summary comes first,
// and its figures agree with the rest of the report.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "cli/json_schema.h"
#include "polysquare/input/read_region.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/pipeline/report.h"

namespace fs = std::filesystem;
using polysquare::test::validate_json;

namespace {

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& e : v) s += e + "\n";
  return s;
}

class Report : public ::testing::Test {
 protected:
  // One meshing run shared by the tests: square_feature (a square with a feature curve) at h = 3.
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("polysquare_report_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    const std::string cmd = std::string(POLYSQUARE_CLI) + " mesh " + POLYSQUARE_DATA_DIR +
                            "/cases/square_feature.geojson --size 3 -o " + (dir_ / "m.msh").string() + " --report " +
                            (dir_ / "r.json").string() + " > /dev/null 2>&1";
    status_ = std::system(cmd.c_str());
    text_ = read_text(dir_ / "r.json");
    schema_ = nlohmann::json::parse(read_text(fs::path(POLYSQUARE_SCHEMA_DIR) / "report.schema.json"));
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static inline fs::path dir_;
  static inline int status_ = -1;
  static inline std::string text_;
  static inline nlohmann::json schema_;
};

TEST_F(Report, CliReportFollowsTheSchemaWithTheSummaryFirst) {
  ASSERT_EQ(WEXITSTATUS(status_), 0);
  ASSERT_FALSE(text_.empty());
  // The summary is the first block of the file and starts with the quad count.
  EXPECT_EQ(text_.rfind("{\n  \"summary\": {\n    \"quads\": ", 0), 0u) << text_.substr(0, 200);
  const nlohmann::json report = nlohmann::json::parse(text_);
  const std::vector<std::string> errors = validate_json(schema_, report);
  EXPECT_TRUE(errors.empty()) << joined(errors);

  // The summary repeats figures found elsewhere in the report.
  const nlohmann::json& s = report["summary"];
  EXPECT_EQ(s["quads"], report["counts"]["quads"]);
  EXPECT_EQ(s["quads"], report["quality"]["quads"]);
  EXPECT_EQ(s["sj_min"], report["quality"]["sj"]["min"]);
  EXPECT_EQ(s["singularities"], report["quality"]["singularities"]);
  EXPECT_EQ(s["singularities"].get<long>(),
            s["interior_singularities"].get<long>() + s["boundary_singularities"].get<long>());
  EXPECT_GT(report["counts"]["feature_edges"].get<long>(), 0);
  // Feature distance relative to h.
  const nlohmann::json& d = report["domain"];
  const double h = report["options"]["size"].get<double>();
  EXPECT_DOUBLE_EQ(h, 3.0);
  EXPECT_NEAR(d["feature_max_distance_over_size"].get<double>(), d["feature_max_distance"].get<double>() / h, 1e-12);
  EXPECT_NEAR(d["feature_node_max_distance_over_size"].get<double>(),
              d["feature_node_max_distance"].get<double>() / h, 1e-12);
}

TEST_F(Report, SchemaRejectsBrokenReports) {
  ASSERT_EQ(WEXITSTATUS(status_), 0);
  const nlohmann::json report = nlohmann::json::parse(text_);
  auto errors_after = [&](auto change) {
    nlohmann::json r = report;
    change(r);
    return validate_json(schema_, r);
  };
  EXPECT_FALSE(errors_after([](nlohmann::json& r) { r.erase("summary"); }).empty());
  EXPECT_FALSE(errors_after([](nlohmann::json& r) { r["summary"].erase("sj_min"); }).empty());
  EXPECT_FALSE(errors_after([](nlohmann::json& r) { r["summary"]["quads"] = "12"; }).empty());
  EXPECT_FALSE(errors_after([](nlohmann::json& r) { r["summary"]["structured_fraction"] = 1.5; }).empty());
  EXPECT_FALSE(errors_after([](nlohmann::json& r) { r["summary"]["sj_min"] = -0.1; }).empty());
  EXPECT_FALSE(errors_after([](nlohmann::json& r) { r["summary"]["version"] = "dev"; }).empty());
  EXPECT_FALSE(errors_after([](nlohmann::json& r) { r["quality"]["triangles"] = 2; }).empty());
  EXPECT_FALSE(errors_after([](nlohmann::json& r) { r["quality"]["sj"]["max"] = 1.2; }).empty());  // via $ref
  EXPECT_FALSE(errors_after([](nlohmann::json& r) { r["domain"].erase("feature_max_distance_over_size"); }).empty());
  EXPECT_FALSE(errors_after([](nlohmann::json& r) { r["options"]["map"] = "tri"; }).empty());
  EXPECT_FALSE(errors_after([](nlohmann::json& r) { r["parts"] = nlohmann::json::array(); }).empty());
  EXPECT_FALSE(errors_after([](nlohmann::json& r) {
                 r["unstructured"].push_back({{"part", 0}, {"subregion", 1}, {"quads", 3}, {"meshed_by", "patch"},
                                              {"at", {1.0}}});
               }).empty());
  // A new key is allowed (later versions may add some).
  EXPECT_TRUE(errors_after([](nlohmann::json& r) { r["summary"]["something_new"] = 1; }).empty());
}

// Every key of the CLI's report has a field of MeshReport: read into the struct and written again, the report is
// the same text (keys, values, order), so no key is dropped, renamed or retyped (an integer read as a number
// would come back as 3.0).
TEST_F(Report, CliReportRoundTripsThroughTheTypedReport) {
  ASSERT_EQ(WEXITSTATUS(status_), 0);
  const polysquare::MeshReport typed = nlohmann::json::parse(text_).get<polysquare::MeshReport>();
  EXPECT_EQ(polysquare::report_text(typed), text_);
  EXPECT_TRUE(typed.quality && typed.domain && typed.groups && typed.summary.quality && typed.input.notes);
  EXPECT_EQ(typed.summary.quads, typed.counts.quads);
}

// The same for mesh_region's report (no quality yet), with a chosen candidate and a partition in it.
TEST(TypedReport, LibraryReportRoundTrips) {
  const polysquare::Region region =
      polysquare::read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/square_feature.geojson");
  polysquare::MeshOptions options;
  options.size.h = 3.0;
  const polysquare::MeshResult result = polysquare::mesh_region(region, options);
  const nlohmann::json j = result.report;
  EXPECT_EQ(nlohmann::json(j.get<polysquare::MeshReport>()).dump(), j.dump());
  EXPECT_FALSE(j.contains("quality"));
  ASSERT_FALSE(result.report.candidates.empty());
  EXPECT_EQ(std::count_if(result.report.candidates[0].begin(), result.report.candidates[0].end(),
                          [](const polysquare::CandidateReport& c) { return c.chosen; }),
            1);
}

// Every key the schema requires, at the top and in every object section (summary, quality, domain, input, ...),
// is written from a field of MeshReport: a report with every optional section set holds them all.
TEST_F(Report, SchemaRequiresOnlyKeysTheTypedReportWrites) {
  polysquare::MeshReport full;
  full.summary.quality.emplace();
  full.input.notes.emplace();
  full.quality.emplace();
  full.domain.emplace();
  full.groups.emplace();
  full.options = nlohmann::json::parse(text_)["options"];  // kept as JSON (see mesh_report.h)
  const nlohmann::json report = full;
  std::vector<std::string> missing;
  std::function<void(const nlohmann::json&, const nlohmann::json&, const std::string&)> check =
      [&](const nlohmann::json& schema, const nlohmann::json& j, const std::string& path) {
        if (!j.is_object()) return;
        for (const auto& key : schema.value("required", nlohmann::json::array()))
          if (!j.contains(key.get<std::string>())) missing.push_back(path + "/" + key.get<std::string>());
        const nlohmann::json properties = schema.value("properties", nlohmann::json::object());
        for (const auto& [key, sub] : properties.items())
          if (j.contains(key)) check(sub, j[key], path + "/" + key);
      };
  check(schema_, report, "");
  EXPECT_TRUE(missing.empty()) << joined(missing);
}

TEST(JsonSchemaValidator, ChecksEachKeywordAndRefusesUnknownOnes) {
  const nlohmann::json schema = nlohmann::json::parse(R"({
    "type": "object", "required": ["n"], "additionalProperties": false,
    "properties": {"n": {"type": "integer", "minimum": 2, "exclusiveMaximum": 5},
                   "p": {"$ref": "#/$defs/p"}, "s": {"type": ["string", "null"], "pattern": "^a"}},
    "$defs": {"p": {"type": "array", "minItems": 2, "maxItems": 2, "items": {"type": "number"}}}})");
  EXPECT_TRUE(validate_json(schema, {{"n", 2}, {"p", {1, 2.5}}, {"s", "ab"}}).empty());
  EXPECT_TRUE(validate_json(schema, {{"n", 4}, {"s", nullptr}}).empty());
  EXPECT_EQ(validate_json(schema, {{"n", 5}}).size(), 1u);
  EXPECT_EQ(validate_json(schema, {{"n", 1}}).size(), 1u);
  EXPECT_EQ(validate_json(schema, {{"n", 2.5}}).size(), 1u);
  EXPECT_EQ(validate_json(schema, {{"n", 3}, {"p", {1}}}).size(), 1u);
  EXPECT_EQ(validate_json(schema, {{"n", 3}, {"p", {1, "x"}}}).size(), 1u);
  EXPECT_EQ(validate_json(schema, {{"n", 3}, {"s", "ba"}}).size(), 1u);
  EXPECT_EQ(validate_json(schema, {{"n", 3}, {"q", 1}}).size(), 1u);
  EXPECT_EQ(validate_json(schema, nlohmann::json::object()).size(), 1u);
  EXPECT_EQ(validate_json(nlohmann::json::parse(R"({"oneOf": []})"), 1).size(), 1u);
}

}  // namespace
