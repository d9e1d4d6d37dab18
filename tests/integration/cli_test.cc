// The `lightfarm` binary end to end: a render writes an EXR whose header says how it was
// made, and bad input fails with a message naming what and where.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

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

class Cli : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("lf_cli_" + std::to_string(::getpid()));
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string Write(const std::string& name, const std::string& text) {
        std::ofstream(dir_ / name) << text;
        return (dir_ / name).string();
    }
    fs::path dir_;
};

TEST_F(Cli, RenderWritesExrWithMetadataAndPng) {
    const std::string exr = (dir_ / "c.exr").string(), png = (dir_ / "c.png").string();
    const RunResult r = Lightfarm("render " + std::string(LF_TEST_SCENES) +
                            "/cornell_box.json -o " + exr + " --png " + png +
                            " --spp 2 --seed 3 --threads 2 --tile 16 --no-progress");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("samples/s"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("NaN"), std::string::npos) << r.output;
    absl::StatusOr<ExrFile> file = ReadExr(exr);
    ASSERT_TRUE(file.ok()) << file.status();
    EXPECT_EQ(file->image.width(), 256);
    for (const char* ch : {"R", "G", "B", "A.R", "B.R", "spp"}) {
        EXPECT_NE(file->image.FindChannel(ch), nullptr) << ch;
    }
    for (const char* key : {"lightfarm.sceneHash", "lightfarm.method", "lightfarm.spp",
                            "lightfarm.seed", "lightfarm.maxDepth", "lightfarm.seconds",
                            "lightfarm.version"}) {
        EXPECT_TRUE(file->attributes.count(key)) << key;
    }
    EXPECT_EQ(std::get<int>(file->attributes.at("lightfarm.spp")), 2);
    EXPECT_TRUE(fs::exists(png));
}

TEST_F(Cli, HelpExplainsEveryCommand) {
    for (const char* cmd : {"--help", "render --help", "bench --help"}) {
        const RunResult r = Lightfarm(cmd);
        EXPECT_EQ(r.status, 0) << cmd;
        EXPECT_NE(r.output.find("Usage"), std::string::npos) << cmd << r.output;
    }
}

TEST_F(Cli, MalformedSceneNamesTheFileAndLine) {
    const std::string scene = Write("bad.json", "{\n  \"camera\": {\n    \"position\": [0, 0,\n");
    const RunResult r = Lightfarm("render " + scene + " -o " + (dir_ / "x.exr").string());
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.output.find("bad.json"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir_ / "x.exr"));
}

TEST_F(Cli, AbsurdOptionsAreRefused) {
    const std::string base = "render " + std::string(LF_TEST_SCENES) + "/cornell_box.json -o " +
                             (dir_ / "x.exr").string();
    EXPECT_NE(Lightfarm(base + " --spp 0").status, 0);
    EXPECT_NE(Lightfarm(base + " --tile 0").status, 0);
    EXPECT_NE(Lightfarm(base + " --max-depth -5").status, 0);
    const RunResult unwritable = Lightfarm(base.substr(0, base.find(" -o ")) +
                                     " -o /nonexistent/dir/x.exr --spp 1 --no-progress");
    EXPECT_NE(unwritable.status, 0);
    EXPECT_NE(unwritable.output.find("/nonexistent/dir/x.exr"), std::string::npos)
        << unwritable.output;
}

}  // namespace
}  // namespace lf
