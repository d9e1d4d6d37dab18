// `lightfarm converge` comparing configurations (sampler, light strategy) end to end on a tiny
// Cornell box: one ladder per configuration against one reference it renders itself and names,
// the summary with the first configuration as the baseline, and bad lists refused before any
// rendering. The equal-time arithmetic is tested on its own (tests/unit/core/error_curve_test.cc).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "lf/core/image_io.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

struct RunResult {
    int status;
    std::string output;  // stdout and stderr
};

RunResult Lightfarm(const std::string& args) {
    const std::string cmd = std::string(LF_BIN_DIR) + "/lightfarm " + args + " 2>&1";
    FILE* pipe = popen(cmd.c_str(), "r");
    std::string out;
    char buf[4096];
    while (size_t n = fread(buf, 1, sizeof buf, pipe)) out.append(buf, n);
    const int status = pclose(pipe);
    return {WEXITSTATUS(status), out};
}

// The rows of a CSV file, each split at commas; the header first.
std::vector<std::vector<std::string>> ReadCsv(const fs::path& path) {
    std::ifstream in(path);
    std::vector<std::vector<std::string>> rows;
    for (std::string line; std::getline(in, line);) {
        rows.push_back(absl::StrSplit(line, ','));
    }
    return rows;
}

class Converge : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("lf_converge_" + std::to_string(::getpid()));
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string Cornell() const { return std::string(LF_TEST_SCENES) + "/cornell_box.json"; }
    fs::path dir_;
};

TEST_F(Converge, ComparesEveryPairOfSamplerAndLightStrategyAgainstOneReference) {
    const fs::path out = dir_ / "product";
    const RunResult r = Lightfarm("converge " + Cornell() + " --out " + out.string() +
                                  " --method path --resolution 16 --max-spp 8 --reference-spp 64 "
                                  "--fit-spp 2:8 "
                                  "--sampler independent,sobol --light-sampling power,bvh "
                                  "--threads 2");
    ASSERT_EQ(r.status, 0) << r.output;

    const auto rows = ReadCsv(out / "convergence.csv");
    ASSERT_EQ(rows.size(), 1u + 4 * 4);  // header, 4 configurations x rungs 1, 2, 4, 8
    EXPECT_EQ(absl::StrJoin(rows[0], ","),
              "method,budget,seconds,rmse,relmse,smape,estimated_relmse,sampler,light_sampling");
    const std::vector<std::pair<std::string, std::string>> configs = {
        {"independent", "power"}, {"independent", "bvh"}, {"sobol", "power"}, {"sobol", "bvh"}};
    for (size_t c = 0; c < configs.size(); ++c) {
        for (int k = 0; k < 4; ++k) {
            const std::vector<std::string>& row = rows[1 + c * 4 + k];
            ASSERT_EQ(row.size(), 9u);
            EXPECT_EQ(row[0], "path");
            EXPECT_EQ(row[1], std::to_string(1 << k));
            EXPECT_EQ(row[7], configs[c].first);
            EXPECT_EQ(row[8], configs[c].second);
            EXPECT_GT(std::stod(row[3]), 0) << absl::StrJoin(row, ",");
        }
    }

    const auto summary = ReadCsv(out / "summary.csv");
    ASSERT_EQ(summary.size(), 1u + 4);
    EXPECT_EQ(summary[0][0], "sampler");
    for (size_t c = 0; c < configs.size(); ++c) {
        const std::vector<std::string>& row = summary[1 + c];
        ASSERT_EQ(row.size(), summary[0].size());
        EXPECT_EQ(row[0], configs[c].first);
        EXPECT_EQ(row[1], configs[c].second);
        EXPECT_EQ(row[2], "2");  // the rungs of --fit-spp 2:8
        EXPECT_EQ(row[3], "8");
        // Slopes in time are left unchecked: rungs of a millisecond are all timing noise.
        EXPECT_TRUE(std::isfinite(std::stod(row[4]))) << absl::StrJoin(row, ",");
        EXPECT_GT(std::stod(row[6]), 0);  // samples/s
    }
    // The baseline's ratios to itself.
    for (int column : {11, 12, 13, 14}) EXPECT_EQ(summary[1][column], "1.0000");
    EXPECT_NE(r.output.find("ratios to independent/power"), std::string::npos) << r.output;

    // The reference: one of the configurations, named in the output and in its EXR.
    const std::string prefix = "own path-traced reference, 64 spp, ";
    const size_t named = r.output.find(prefix);
    ASSERT_NE(named, std::string::npos) << r.output;
    absl::StatusOr<ExrFile> reference = ReadExr((out / "reference.exr").string());
    ASSERT_TRUE(reference.ok()) << reference.status();
    const auto& a = reference->attributes;
    const std::string config = std::get<std::string>(a.at("lightfarm.sampler")) + "/" +
                               std::get<std::string>(a.at("lightfarm.light_sampling"));
    EXPECT_EQ(r.output.substr(named + prefix.size(), config.size()), config) << r.output;
    EXPECT_EQ(std::get<int>(a.at("lightfarm.spp")), 64);
    EXPECT_EQ(std::get<std::string>(a.at("lightfarm.seed")), "1");  // the ladders' seed 0, plus 1
    EXPECT_NE(std::get<std::string>(a.at("lightfarm.converge.reference")).find(config),
              std::string::npos);
    EXPECT_GT(fs::file_size(out / "convergence.png"), 1000u);
}

TEST_F(Converge, ExplicitConfigurationsKeepTheirOrderAndTheFirstIsTheBaseline) {
    const fs::path out = dir_ / "explicit";
    const RunResult r = Lightfarm("converge " + Cornell() + " --out " + out.string() +
                                  " --method path --resolution 16 --max-spp 8 --reference-spp 64 "
                                  "--compare sobol/bvh,independent/power --threads 2");
    ASSERT_EQ(r.status, 0) << r.output;
    const auto summary = ReadCsv(out / "summary.csv");
    ASSERT_EQ(summary.size(), 3u);
    EXPECT_EQ(summary[1][0] + "/" + summary[1][1], "sobol/bvh");
    EXPECT_EQ(summary[2][0] + "/" + summary[2][1], "independent/power");
    EXPECT_EQ(summary[1][11], "1.0000");
    // The default --fit-spp 16:1024 holds no rung of 1 to 8: the whole ladder, and it says so.
    EXPECT_EQ(summary[1][2], "1");
    EXPECT_EQ(summary[1][3], "8");
    EXPECT_NE(r.output.find("fitted over the whole ladder"), std::string::npos) << r.output;
}

TEST_F(Converge, BadListsAreRefusedBeforeRendering) {
    const std::string base = "converge " + Cornell() + " --out " + (dir_ / "bad").string() +
                             " --resolution 16 --max-spp 8 ";
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"--compare sobol/foo",
         "--compare sobol/foo: \"sobol/foo\" is not SAMPLER/LIGHTS with SAMPLER independent or "
         "sobol and LIGHTS power or bvh"},
        {"--compare sobol", "--compare sobol: \"sobol\" is not SAMPLER/LIGHTS"},
        {"--compare sobol/bvh,sobol/bvh", "\"sobol/bvh\" is listed twice"},
        {"--sampler sobol,halton",
         "--sampler sobol,halton: \"halton\" is not independent or sobol"},
        {"--light-sampling power,", "--light-sampling power,: \"\" is not power or bvh"},
        {"--compare sobol/bvh --sampler independent", "excludes"},
        {"--fit-spp 8:4", "--fit-spp 8:4: expected FROM:TO"},
        {"--fit-spp 16:64", "--fit-spp 16:64 holds fewer than two rungs of the ladder 1 to 8 spp"},
    };
    for (const auto& [args, message] : cases) {
        const RunResult r = Lightfarm(base + args);
        EXPECT_NE(r.status, 0) << args;
        EXPECT_NE(r.output.find(message), std::string::npos) << args << "\n" << r.output;
        EXPECT_FALSE(fs::exists(dir_ / "bad" / "convergence.csv")) << args;
    }
}

}  // namespace
}  // namespace lf
