// The `lightfarm` binary end to end: a render writes an EXR whose header says how it was
// made, and bad input fails with a message naming what and where.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <stb_image.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "absl/cleanup/cleanup.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "image_files.h"
#include "lf/core/false_color.h"
#include "lf/core/image_io.h"
#include "vdb_files.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

struct RunResult {
    int status;
    std::string output;  // stdout and stderr
};

// `command` (a shell command line), its stderr with its stdout.
RunResult RunCommand(const std::string& command) {
    const std::string cmd = command + " 2>&1";
    FILE* pipe = popen(cmd.c_str(), "r");
    std::string out;
    char buf[4096];
    while (size_t n = fread(buf, 1, sizeof buf, pipe)) out.append(buf, n);
    const int status = pclose(pipe);
    return {WEXITSTATUS(status), out};
}

RunResult Lightfarm(const std::string& args) {
    return RunCommand(std::string(LF_BIN_DIR) + "/lightfarm " + args);
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
    const RunResult r =
        Lightfarm("render " + std::string(LF_TEST_SCENES) + "/cornell_box.json -o " + exr +
                  " --png " + png + " --spp 2 --seed 3 --threads 2 --tile 16 --no-progress");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("samples/s"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("NaN"), std::string::npos) << r.output;
    absl::StatusOr<ExrFile> file = ReadExr(exr);
    ASSERT_TRUE(file.ok()) << file.status();
    EXPECT_EQ(file->image.width(), 256);
    for (const char* ch : {"R", "G", "B", "A.R", "B.R", "spp"}) {
        EXPECT_NE(file->image.FindChannel(ch), nullptr) << ch;
    }
    for (const char* key :
         {"lightfarm.sceneHash", "lightfarm.method", "lightfarm.spp", "lightfarm.seed",
          "lightfarm.maxDepth", "lightfarm.seconds", "lightfarm.version"}) {
        EXPECT_TRUE(file->attributes.count(key)) << key;
    }
    EXPECT_EQ(std::get<int>(file->attributes.at("lightfarm.spp")), 2);
    EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.sampler")), "sobol");
    // Two samples leave a typical pixel about 20 % off: flagged, in the log and header.
    EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.highVariance")), "yes");
    EXPECT_GT(std::get<double>(file->attributes.at("lightfarm.estimatedRelMse")), 0.01);
    EXPECT_GT(std::get<double>(file->attributes.at("lightfarm.estimatedError")), 0.1);
    EXPECT_NE(r.output.find("high variance"), std::string::npos) << r.output;
    EXPECT_TRUE(fs::exists(png));
}

// The demo scene (tests/scenes/gltf_demo), laid out as Blender's exporter writes a file: the
// lights extension required, emissive strength, glass with a volume, gold, a textured floor, a
// sun and a spot light. It renders with every sample finite and its camera in the header.
TEST_F(Cli, GltfDemoSceneRendersEveryFeatureWithoutAnInvalidSample) {
    const std::string exr = (dir_ / "demo.exr").string();
    const RunResult r =
        Lightfarm("render " + std::string(LF_TEST_SCENES) + "/gltf_demo/demo.gltf -o " + exr +
                  " --spp 4 --resolution 48x32 --camera Camera --no-progress");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find(" 0 NaN/Inf samples"), std::string::npos) << r.output;
    absl::StatusOr<ExrFile> file = ReadExr(exr);
    ASSERT_TRUE(file.ok()) << file.status();
    EXPECT_EQ(file->image.width(), 48);
    EXPECT_EQ(file->image.height(), 32);
    EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.invalidSamples")), "0");
    EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.camera")), "Camera");
    double sum = 0;
    for (const float v : *file->image.FindChannel("R")) sum += v;
    EXPECT_GT(sum, 0);
}

// The high-variance flag follows the typical pixel, not the light's few half-covered edge
// pixels: the Cornell box at 64^2 measured 0.037 to 0.041 estimated relMSE at 4 spp (flagged)
// and 0.0012 at 256 spp (not), over seeds 0 to 2.
TEST_F(Cli, HighVarianceFlagsFourSamplesAndNotTwoHundredFiftySix) {
    std::ifstream in(std::string(LF_TEST_SCENES) + "/cornell_box.json");
    nlohmann::json scene = nlohmann::json::parse(in);
    scene["camera"]["resolution"] = {64, 64};
    const std::string path = Write("cornell_64.json", scene.dump());
    for (const auto& [spp, flagged] : {std::pair{4, "yes"}, std::pair{256, "no"}}) {
        const std::string exr = (dir_ / ("c" + std::to_string(spp) + ".exr")).string();
        const RunResult r = Lightfarm("render " + path + " -o " + exr + " --spp " +
                                      std::to_string(spp) + " --threads 2 --no-progress");
        ASSERT_EQ(r.status, 0) << r.output;
        absl::StatusOr<ExrFile> file = ReadExr(exr);
        ASSERT_TRUE(file.ok()) << file.status();
        EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.highVariance")), flagged)
            << spp << " spp, estimated relMSE "
            << std::get<double>(file->attributes.at("lightfarm.estimatedRelMse"));
    }
}

TEST_F(Cli, HelpExplainsEveryCommand) {
    for (const char* cmd :
         {"--help", "render --help", "bench --help", "converge --help", "plan --help"}) {
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

namespace lf {
namespace {

TEST_F(Cli, AutoPicksRadiosityForLambertianScenesAndSaysWhy) {
    const std::string scene = std::string(LF_TEST_SCENES) + "/cornell_box.json";
    const std::string exr = (dir_ / "r.exr").string(), solution = (dir_ / "r.sol").string();
    const RunResult r = Lightfarm("render " + scene + " -o " + exr +
                                  " --method auto --patches 300 --spp 1 --no-progress "
                                  "--save-solution " +
                                  solution + " --export-ply " + (dir_ / "r.ply").string());
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("method radiosity (every material is Lambertian)"), std::string::npos)
        << r.output;
    absl::StatusOr<ExrFile> file = ReadExr(exr);
    ASSERT_TRUE(file.ok()) << file.status();
    EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.method")), "radiosity");
    EXPECT_LT(std::get<double>(file->attributes.at("lightfarm.radiosity.residual")), 1e-4);
    EXPECT_TRUE(fs::exists(dir_ / "r.ply"));

    // The saved solution renders the same image without solving again.
    const std::string again = (dir_ / "again.exr").string();
    const RunResult loaded = Lightfarm("render " + scene + " -o " + again +
                                       " --method radiosity --patches 300 --spp 1 --no-progress "
                                       "--load-solution " +
                                       solution);
    ASSERT_EQ(loaded.status, 0) << loaded.output;
    absl::StatusOr<ExrFile> second = ReadExr(again);
    ASSERT_TRUE(second.ok());
    EXPECT_EQ(std::get<std::string>(second->attributes.at("lightfarm.radiosity.loaded")), "yes");
    EXPECT_EQ(*second->image.FindChannel("R"), *file->image.FindChannel("R"));
}

TEST_F(Cli, RadiosityRefusesWhatItCannotModel) {
    const RunResult r =
        Lightfarm("render " + std::string(LF_TEST_SCENES) +
                  "/khronos/AlphaBlendModeTest/AlphaBlendModeTest.gltf --camera auto -o " +
                  (dir_ / "a.exr").string() + " --method radiosity --spp 1 --no-progress");
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.output.find("which radiosity does not model"), std::string::npos) << r.output;
    // materials.json's spheres are meshed; its glass, mirror and glossy balls have no diffuse
    // part, which the render names.
    const std::string scene = std::string(LF_TEST_SCENES) + "/materials.json";
    const RunResult spheres =
        Lightfarm("render " + scene + " -o " + (dir_ / "m.exr").string() +
                  " --method radiosity --patches 300 --resolution 16x16 --spp 1 --no-progress");
    EXPECT_EQ(spheres.status, 0) << spheres.output;
    EXPECT_NE(spheres.output.find("\"glass\" (dielectric), \"mirror\" (mirror)"), std::string::npos)
        << spheres.output;
    const RunResult automatic = Lightfarm("render " + scene + " -o " + (dir_ / "m.exr").string() +
                                          " --method auto --spp 1 --no-progress");
    EXPECT_EQ(automatic.status, 0) << automatic.output;
    // Auto sees the caustics of its small lamp and its point light through glass and a mirror.
    EXPECT_NE(automatic.output.find("method bdpt (caustics (L S+ D E): light from emitter "
                                    "\"light\" (0.74 % of the scene's bounding surface), 1 "
                                    "point light through mirror, glass; the path tracer cannot "
                                    "sample those of the 1 point light at all)"),
              std::string::npos)
        << automatic.output;
}

// --method auto reads the scene's light transport: caustics from a small lamp through glass
// and a mirror take bdpt; a lit plane alone (no interreflection, no caustics) takes Whitted,
// exact there; the Cornell box (all Lambertian) radiosity; a scene without lights no solve.
TEST_F(Cli, AutoPicksTheMethodTheSceneRequiresAndSaysWhy) {
    const auto method_line = [&](const std::string& scene) {
        const RunResult r = Lightfarm("render " + scene + " -o " + (dir_ / "a.exr").string() +
                                      " --method auto --spp 2 --resolution 8x8 --no-progress");
        EXPECT_EQ(r.status, 0) << r.output;
        const size_t at = r.output.find(" method ");
        return at == std::string::npos ? r.output
                                       : r.output.substr(at + 1, r.output.find('\n', at) - at - 1);
    };
    EXPECT_EQ(method_line(std::string(LF_TEST_SCENES) + "/caustic.json")
                  .rfind("method bdpt (caustics (L S+ D E): light from emitter \"light\" (0.", 0),
              0u);
    const std::string plane =
        Write("plane.json", R"({"camera": {"position": [0, 3, 0], "look_at": [0, 0, 0],
                                "up": [0, 0, 1], "fov_y_deg": 60, "resolution": [16, 16]},
            "materials": {"grey": {"type": "lambert", "reflectance": [0.5, 0.5, 0.5]}},
            "shapes": [{"type": "quad", "material": "grey",
                        "vertices": [[-5, 0, -5], [-5, 0, 5], [5, 0, 5], [5, 0, -5]]}],
            "lights": [{"type": "point", "position": [0, 2, 0], "power": [5, 5, 5]}]})");
    EXPECT_EQ(method_line(plane),
              "method whitted (no interreflection and no caustics: classic ray tracing is exact "
              "here (point-like lights only))");
    EXPECT_EQ(method_line(std::string(LF_TEST_SCENES) + "/cornell_box.json"),
              "method radiosity (every material is Lambertian)");
    const std::string dark =
        Write("dark.json", R"({"camera": {"position": [0, 3, 0], "look_at": [0, 0, 0],
                               "up": [0, 0, 1], "fov_y_deg": 60, "resolution": [16, 16]},
            "materials": {"grey": {"type": "lambert", "reflectance": [0.5, 0.5, 0.5]}},
            "shapes": [{"type": "quad", "material": "grey",
                        "vertices": [[-5, 0, -5], [-5, 0, 5], [5, 0, 5], [5, 0, -5]]}]})");
    EXPECT_EQ(method_line(dark),
              "method path (the scene has no lights: the image is black whatever the method)");
}

// Radiosity takes textures and principled materials by their diffuse part: a textured lambert
// room is radiosity's under auto; a metal one (no diffuse part) auto leaves to the path tracer
// and says what radiosity would drop (two walls that light each other: Whitted would miss that).
TEST_F(Cli, AutoSaysWhatRadiosityWouldDrop) {
    Write("wood.png", lf::testing::PngBytes(1, 1, 3, {200, 100, 50}));
    auto scene = [&](const std::string& material) {
        return Write("textured.json", R"({"camera": {"position": [0, 0, -3], "look_at": [0, 0, 0],
            "fov_y_deg": 40, "resolution": [8, 8]},
            "materials": {"wood": )" + material +
                                          R"(,
                          "lamp": {"type": "lambert", "reflectance": [0, 0, 0],
                                   "emission": [1, 1, 1]}},
            "shapes": [{"type": "quad", "material": "wood",
                        "vertices": [[-1, -1, 0], [-1, 1, 0], [1, 1, 0], [1, -1, 0]]},
                       {"type": "quad", "material": "wood",
                        "vertices": [[-1, -1, -1], [-1, -1, 0], [1, -1, 0], [1, -1, -1]]},
                       {"type": "quad", "material": "lamp",
                        "vertices": [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1]]}]})");
    };
    const std::string textured = scene(R"({"type": "lambert", "base_color_texture": "wood.png"})");
    const std::string exr = (dir_ / "t.exr").string();
    const RunResult automatic =
        Lightfarm("render " + textured + " -o " + exr + " --method auto --spp 1 --no-progress");
    ASSERT_EQ(automatic.status, 0) << automatic.output;
    EXPECT_NE(automatic.output.find("method radiosity (every material is Lambertian)"),
              std::string::npos)
        << automatic.output;

    const std::string principled = scene(R"({"type": "principled", "metallic": 1})");
    const RunResult plan = Lightfarm("plan " + principled + " --pilot-spp 2 --threads 2");
    EXPECT_NE(plan.output.find("method (--method auto): path, because radiosity would keep only "
                               "the diffuse parts (dropping no diffuse part (rendered black): "
                               "\"wood\" (principled); specular reflection: \"wood\")"),
              std::string::npos)
        << plan.output;
    const RunResult radiosity =
        Lightfarm("plan " + principled + " --method radiosity --pilot-spp 2 --threads 2");
    EXPECT_NE(radiosity.output.find("radiosity keeps the diffuse parts only; it drops no diffuse "
                                    "part (rendered black): \"wood\" (principled)"),
              std::string::npos)
        << radiosity.output;
}

TEST_F(Cli, ConvergeWritesTheCsvAndThePlot) {
    const fs::path out = dir_ / "conv";
    const RunResult r = Lightfarm("converge " + std::string(LF_TEST_SCENES) +
                                  "/cornell_box.json --out " + out.string() +
                                  " --resolution 16 --max-spp 4 --reference-spp 16 "
                                  "--min-patches 100 --max-patches 200 --threads 2");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("no reference given: own path-traced reference, 16 spp"),
              std::string::npos)
        << r.output;
    std::ifstream csv(out / "convergence.csv");
    std::string line;
    ASSERT_TRUE(std::getline(csv, line));
    EXPECT_EQ(line,
              "method,budget,seconds,rmse,relmse,smape,estimated_relmse,sampler,light_sampling,"
              "region_rmse,region_relmse");
    std::vector<std::string> rows;
    while (std::getline(csv, line)) rows.push_back(line);
    // spp 1, 2, 4 and patch targets 100, 200.
    ASSERT_EQ(rows.size(), 5u);
    EXPECT_EQ(rows[0].rfind("path,1,", 0), 0u) << rows[0];
    EXPECT_EQ(rows[3].rfind("radiosity,", 0), 0u) << rows[3];
    for (const std::string& row : rows) {
        EXPECT_EQ(std::count(row.begin(), row.end(), ','), 10) << row;
        EXPECT_EQ(row.find("nan"), std::string::npos) << row;
    }
    // The image's own estimate from 2 spp on, for path rows only; the light strategy for path
    // rows only.
    EXPECT_NE(rows[0].find(",,sobol,bvh"), std::string::npos) << rows[0];
    EXPECT_NE(rows[1].find("e-"), std::string::npos) << rows[1];
    EXPECT_EQ(rows[1].find(",,sobol"), std::string::npos) << rows[1];
    EXPECT_NE(rows[3].find(",,sobol,"), std::string::npos) << rows[3];
    EXPECT_EQ(rows[3].back(), ',') << rows[3];
    EXPECT_GT(fs::file_size(out / "convergence.png"), 1000u);

    // Radiosity's refusal (of alpha-blended materials; spheres it meshes) comes before any
    // rendering.
    const RunResult refused =
        Lightfarm("converge " + std::string(LF_TEST_SCENES) +
                  "/khronos/AlphaBlendModeTest/AlphaBlendModeTest.gltf --camera auto --out " +
                  out.string() + " --method both");
    EXPECT_NE(refused.status, 0);
    EXPECT_NE(refused.output.find("radiosity cannot model this scene: material"), std::string::npos)
        << refused.output;
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

// `converge` comparing configurations (sampler, light strategy): one ladder per configuration
// against one reference it renders itself and names, the first configuration the baseline, bad
// lists refused before any rendering. The equal-time arithmetic is tested on its own
// (tests/unit/core/error_curve_test.cc).
TEST_F(Cli, ConvergeComparesEveryPairOfSamplerAndLightStrategyAgainstOneReference) {
    const fs::path out = dir_ / "product";
    const RunResult r = Lightfarm("converge " + std::string(LF_TEST_SCENES) + "/cornell_box.json" +
                                  " --out " + out.string() +
                                  " --method path --resolution 16 --max-spp 32 --reference-spp 64 "
                                  "--fit-spp 2:32 "
                                  "--sampler independent,sobol --light-sampling power,bvh "
                                  "--threads 2");
    ASSERT_EQ(r.status, 0) << r.output;

    const auto rows = ReadCsv(out / "convergence.csv");
    // Header, 4 configurations x rungs 1 to 32: rungs spanning 16x in time per configuration, so
    // that the ladders share time however timing noise scatters rungs of a millisecond.
    ASSERT_EQ(rows.size(), 1u + 4 * 6);
    EXPECT_EQ(absl::StrJoin(rows[0], ","),
              "method,budget,seconds,rmse,relmse,smape,estimated_relmse,sampler,light_sampling,"
              "region_rmse,region_relmse");
    const std::vector<std::pair<std::string, std::string>> configs = {
        {"independent", "power"}, {"independent", "bvh"}, {"sobol", "power"}, {"sobol", "bvh"}};
    for (size_t c = 0; c < configs.size(); ++c) {
        for (int k = 0; k < 6; ++k) {
            const std::vector<std::string>& row = rows[1 + c * 6 + k];
            ASSERT_EQ(row.size(), 11u);
            EXPECT_EQ(row[9], "");  // no --region
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
        EXPECT_EQ(row[2], "2");  // the rungs of --fit-spp 2:32
        EXPECT_EQ(row[3], "32");
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
                               std::get<std::string>(a.at("lightfarm.lightSampling"));
    EXPECT_EQ(r.output.substr(named + prefix.size(), config.size()), config) << r.output;
    EXPECT_EQ(std::get<int>(a.at("lightfarm.spp")), 64);
    EXPECT_EQ(std::get<std::string>(a.at("lightfarm.seed")), "1");  // the ladders' seed 0, plus 1
    EXPECT_NE(std::get<std::string>(a.at("lightfarm.converge.reference")).find(config),
              std::string::npos);
    EXPECT_GT(fs::file_size(out / "convergence.png"), 1000u);
}

TEST_F(Cli, ConvergeExplicitConfigurationsKeepTheirOrderAndTheFirstIsTheBaseline) {
    const fs::path out = dir_ / "explicit";
    const RunResult r = Lightfarm("converge " + std::string(LF_TEST_SCENES) + "/cornell_box.json" +
                                  " --out " + out.string() +
                                  " --method path --resolution 16 --max-spp 8 --reference-spp 64 "
                                  "--compare sobol/bvh,independent/power --threads 2 "
                                  "--region 4,8,6,5");
    ASSERT_EQ(r.status, 0) << r.output;
    // --region: each row's region errors, measured over those 30 pixels only, differ from the
    // whole image's; the summary's region ratio of the baseline to itself is 1.
    const auto rows = ReadCsv(out / "convergence.csv");
    ASSERT_EQ(rows.size(), 1u + 2 * 4);
    for (size_t i = 1; i < rows.size(); ++i) {
        ASSERT_EQ(rows[i].size(), 11u);
        EXPECT_GT(std::stod(rows[i][9]), 0) << absl::StrJoin(rows[i], ",");
        EXPECT_NE(rows[i][9], rows[i][3]);
    }
    EXPECT_NE(r.output.find("region 4,8 6x5:"), std::string::npos) << r.output;
    const auto summary = ReadCsv(out / "summary.csv");
    ASSERT_EQ(summary.size(), 3u);
    ASSERT_EQ(summary[0][summary[0].size() - 2], "region_rmse_ratio_mean");
    EXPECT_EQ(summary[1][summary[0].size() - 3], "1.0000");
    EXPECT_EQ(summary[1].back(), "path");
    EXPECT_EQ(summary[1][0] + "/" + summary[1][1], "sobol/bvh");
    EXPECT_EQ(summary[2][0] + "/" + summary[2][1], "independent/power");
    EXPECT_EQ(summary[1][11], "1.0000");
    // The default --fit-spp 16:1024 holds no rung of 1 to 8: the whole ladder, and it says so.
    EXPECT_EQ(summary[1][2], "1");
    EXPECT_EQ(summary[1][3], "8");
    EXPECT_NE(r.output.find("fitted over the whole ladder"), std::string::npos) << r.output;
}

TEST_F(Cli, ConvergeBadListsAreRefusedBeforeRendering) {
    const std::string base = "converge " + std::string(LF_TEST_SCENES) + "/cornell_box.json" +
                             " --out " + (dir_ / "bad").string() + " --resolution 16 --max-spp 8 ";
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"--compare sobol/foo",
         "--compare sobol/foo: \"sobol/foo\" is not [METHOD/]SAMPLER/LIGHTS with METHOD path, "
         "light, bdpt or ppm, SAMPLER independent or sobol and LIGHTS power or bvh"},
        {"--compare sobol", "--compare sobol: \"sobol\" is not [METHOD/]SAMPLER/LIGHTS"},
        {"--compare whitted/sobol/bvh", "\"whitted/sobol/bvh\" is not [METHOD/]SAMPLER/LIGHTS"},
        {"--compare sobol/bvh,sobol/bvh", "\"sobol/bvh\" is listed twice"},
        {"--sampler sobol,halton",
         "--sampler sobol,halton: \"halton\" is not independent or sobol"},
        {"--light-sampling power,", "--light-sampling power,: \"\" is not power or bvh"},
        {"--compare sobol/bvh --sampler independent", "excludes"},
        {"--fit-spp 8:4", "--fit-spp 8:4: expected FROM:TO"},
        {"--region 1,2,3", "--region 1,2,3: expected X,Y,W,H"},
        {"--region 0,0,0,4", "--region 0,0,0,4: expected X,Y,W,H"},
        {"--region 10,0,8,8", "--region 10,0,8,8 leaves the 16x16 image"},
        {"--fit-spp 16:64", "--fit-spp 16:64 holds fewer than two rungs of the ladder 1 to 8 spp"},
    };
    for (const auto& [args, message] : cases) {
        const RunResult r = Lightfarm(base + args);
        EXPECT_NE(r.status, 0) << args;
        EXPECT_NE(r.output.find(message), std::string::npos) << args << "\n" << r.output;
        EXPECT_FALSE(fs::exists(dir_ / "bad" / "convergence.csv")) << args;
    }
}

TEST_F(Cli, TargetErrorRecordsTheEstimateInTheHeader) {
    const std::string exr = (dir_ / "t.exr").string();
    const RunResult r =
        Lightfarm("render " + std::string(LF_TEST_SCENES) + "/cornell_box.json -o " + exr +
                  " --spp 4 --target-error 0.3 --time-limit 60 --threads 2 "
                  "--no-progress");
    ASSERT_EQ(r.status, 0) << r.output;
    // Two measures, each named: the image's, and the per-tile one the target bounds.
    EXPECT_NE(r.output.find("estimated relative error of the whole image "), std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("--target-error 0.3 bounds each tile's error: worst tile "),
              std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find(", 0 of 64 tiles above it"), std::string::npos) << r.output;
    absl::StatusOr<ExrFile> file = ReadExr(exr);
    ASSERT_TRUE(file.ok()) << file.status();
    EXPECT_EQ(std::get<double>(file->attributes.at("lightfarm.targetError")), 0.3);
    EXPECT_LE(std::get<double>(file->attributes.at("lightfarm.adaptive.worstTileError")), 0.3);
    EXPECT_GT(std::get<double>(file->attributes.at("lightfarm.estimatedError")), 0);
    const std::vector<float>& spp = *file->image.FindChannel("spp");
    EXPECT_GE(*std::min_element(spp.begin(), spp.end()), 4);
    EXPECT_EQ(*std::max_element(spp.begin(), spp.end()),
              std::get<int>(file->attributes.at("lightfarm.spp")));
}

// --noise-threshold without --spp starts every pixel at Cycles' automatic minimum (0.1: 32), the
// header names the threshold, `plan` explains it, and what cannot combine is refused by name.
TEST_F(Cli, NoiseThresholdUsesCyclesMinimumAndRefusesWhatCannotCombine) {
    const std::string scene = std::string(LF_TEST_SCENES) + "/cornell_box.json";
    const std::string exr = (dir_ / "n.exr").string();
    const RunResult r =
        Lightfarm("render " + scene + " -o " + exr +
                  " --resolution 32 --noise-threshold 0.1 --threads 2 --no-progress");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("--noise-threshold 0.1: 0 of 1024 pixels not converged"),
              std::string::npos)
        << r.output;
    absl::StatusOr<ExrFile> file = ReadExr(exr);
    ASSERT_TRUE(file.ok()) << file.status();
    EXPECT_EQ(std::get<double>(file->attributes.at("lightfarm.noiseThreshold")), 0.1);
    EXPECT_EQ(std::get<int>(file->attributes.at("lightfarm.adaptive.minSpp")), 32);
    const std::vector<float>& spp = *file->image.FindChannel("spp");
    EXPECT_EQ(*std::min_element(spp.begin(), spp.end()), 32);

    const RunResult both = Lightfarm("render " + scene + " -o " + exr +
                                     " --noise-threshold 0.1 --target-error 0.1 --no-progress");
    EXPECT_NE(both.status, 0);
    EXPECT_NE(both.output.find("pick one"), std::string::npos) << both.output;
    const RunResult bdpt = Lightfarm("render " + scene + " -o " + exr +
                                     " --noise-threshold 0.1 --method bdpt --no-progress");
    EXPECT_NE(bdpt.status, 0);
    EXPECT_NE(bdpt.output.find("method \"bdpt\" has no adaptive sampling"), std::string::npos)
        << bdpt.output;
    const RunResult radiosity =
        Lightfarm("render " + scene + " -o " + exr +
                  " --noise-threshold 0.1 --method radiosity --no-progress");
    EXPECT_NE(radiosity.status, 0);
    EXPECT_NE(radiosity.output.find("no per-pixel samples to stop"), std::string::npos)
        << radiosity.output;
    const RunResult plan =
        Lightfarm("plan " + scene + " --noise-threshold 0.01 --method path --resolution 32");
    ASSERT_EQ(plan.status, 0) << plan.output;
    EXPECT_NE(plan.output.find("takes --spp 64 samples (Cycles' automatic minimum for 0.01 is 64)"),
              std::string::npos)
        << plan.output;
    // plan refuses what render refuses.
    for (const char* method : {"radiosity", "bdpt"}) {
        const RunResult refused = Lightfarm("plan " + scene + " --noise-threshold 0.01 --method " +
                                            method + " --resolution 32");
        EXPECT_NE(refused.status, 0) << method;
        EXPECT_NE(refused.output.find(std::string("method \"") + method +
                                      "\" has no per-pixel samples to stop"),
                  std::string::npos)
            << refused.output;
    }
}

// `plan` lists the environment among the lights, and a material whose emission texture has no
// lit texel (glTF exports give emissiveFactor 1 and a black texture) is not an emitter.
TEST_F(Cli, PlanListsTheEnvironmentAndSkipsEmissionTexturesWithoutLight) {
    std::ofstream(dir_ / "black.png", std::ios::binary)
        << testing::PngBytes(2, 2, 3, std::vector<uint8_t>(12, 0));
    const std::string scene = Write("sky.json", R"({
      "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov_y_deg": 40,
                 "resolution": [8, 8]},
      "materials": {"dark": {"type": "principled", "base_color": [0.5, 0.5, 0.5],
                             "emission": [1, 1, 1], "emission_texture": {"file": "black.png"}}},
      "shapes": [{"type": "quad", "material": "dark",
                  "vertices": [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]}],
      "lights": [{"type": "environment", "radiance": [0.5, 0.5, 0.5]}]})");
    const RunResult r = Lightfarm("plan " + scene + " --pilot-spp 2 --threads 2");
    ASSERT_EQ(r.status, 0) << r.output;
    for (const char* text :
         {"lights: 0 emissive triangles", "a uniform environment (0.5, 0.5, 0.5)"}) {
        EXPECT_NE(r.output.find(text), std::string::npos) << text << "\n" << r.output;
    }
}

// `plan` lists the media with their grids, auto takes the path tracer for scattering media,
// and plan and render refuse a method that does not render them, naming both.
TEST_F(Cli, PlanListsMediaAndMethodsRefuseWhatTheyDoNotRender) {
    std::ofstream(dir_ / "smoke.vdb", std::ios::binary)
        << testing::VdbBytes({testing::ConstantGrid("density", 0.5f, 4, 0.25)});
    const std::string scene = Write("fog.json", R"({
      "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov_y_deg": 40,
                 "resolution": [8, 8]},
      "materials": {"lamp": {"type": "lambert", "reflectance": [0.5, 0.5, 0.5],
                             "emission": [1, 1, 1]},
                    "boundary": {"type": "interface"}},
      "media": {"fog": {"type": "homogeneous", "sigma_s": [0.5, 0.5, 0.5], "g": 0.3},
                "smoke": {"type": "grid", "file": "smoke.vdb", "sigma_a": [1, 1, 1]}},
      "shapes": [{"type": "quad", "material": "lamp",
                  "vertices": [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]},
                 {"type": "sphere", "material": "boundary", "center": [0, 0, 1],
                  "radius": 0.5, "interior": "smoke", "exterior": "fog"}]})");
    const RunResult r = Lightfarm("plan " + scene + " --pilot-spp 2 --threads 2");
    ASSERT_EQ(r.status, 0) << r.output;
    for (const char* text :
         {"media:\n  fog: homogeneous, sigma_a (0, 0, 0), sigma_s (0.5, 0.5, 0.5) m^-1, g 0.3\n",
          "  smoke: grid (at density 1), sigma_a (1, 1, 1), sigma_s (0, 0, 0) m^-1, g 0, density "
          "smoke.vdb#density 4x4x4 (0.000244 MiB)\n",
          "method (--method auto): path, because material \"boundary\" is an interface between "
          "media: only the path tracer and bdpt render it"}) {
        EXPECT_NE(r.output.find(text), std::string::npos) << text << "\n" << r.output;
    }
    EXPECT_EQ(r.output.find("  light "), std::string::npos) << "light costed:\n" << r.output;
    for (const std::string& command :
         {"plan " + scene + " --method light --pilot-spp 2",
          "render " + scene + " -o " + (dir_ / "x.exr").string() + " --method light --spp 1"}) {
        const RunResult refused = Lightfarm(command);
        EXPECT_NE(refused.status, 0) << command;
        EXPECT_NE(refused.output.find("method light: material \"boundary\" is an interface between "
                                      "media: not yet supported by light; use --method path"),
                  std::string::npos)
            << command << "\n"
            << refused.output;
    }
}

// OpenVDB is loaded with liblf_vdb.so when a grid is read, not at every start: the programs do
// not link it. A lightfarm without the module renders everything else and says what a grid
// needs; one with the module in ../lib/lightfarm (an install's layout) reads grids.
TEST_F(Cli, OpenVdbIsLoadedOnlyToReadAGrid) {
    for (const char* program : {"lightfarm", "lightfarm-server", "lightfarm-worker"}) {
        const RunResult linked = RunCommand("ldd " + std::string(LF_BIN_DIR) + "/" + program);
        ASSERT_EQ(linked.status, 0) << linked.output;
        EXPECT_EQ(linked.output.find("libopenvdb"), std::string::npos) << program;
    }
    // Copies of the program beside the build's (a /tmp mounted noexec would not run them).
    const fs::path root =
        fs::path(LF_BIN_DIR).parent_path() / ("cli_vdb_" + std::to_string(::getpid()));
    fs::remove_all(root);
    const absl::Cleanup remove_copies = [&root] { fs::remove_all(root); };
    fs::create_directories(root / "alone");
    fs::create_directories(root / "install" / "bin");
    fs::create_directories(root / "install" / "lib" / "lightfarm");
    fs::copy_file(fs::path(LF_BIN_DIR) / "lightfarm", root / "alone" / "lightfarm");
    fs::copy_file(fs::path(LF_BIN_DIR) / "lightfarm", root / "install" / "bin" / "lightfarm");
    fs::copy_file(fs::path(LF_BIN_DIR) / "liblf_vdb.so",
                  root / "install" / "lib" / "lightfarm" / "liblf_vdb.so");
    const std::string alone = (root / "alone" / "lightfarm").string(),
                      installed = (root / "install" / "bin" / "lightfarm").string();

    const RunResult cornell =
        RunCommand(alone + " plan " + std::string(LF_TEST_SCENES) +
                   "/cornell_box.json --pilot-spp 2 --resolution 16x16 --threads 1");
    EXPECT_EQ(cornell.status, 0) << cornell.output;
    std::ofstream(dir_ / "smoke.vdb", std::ios::binary)
        << testing::VdbBytes({testing::ConstantGrid("density", 0.5f, 4, 0.25)});
    const std::string scene = Write("smoke.json", R"({
      "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov_y_deg": 40,
                 "resolution": [8, 8]},
      "materials": {"boundary": {"type": "interface"}},
      "media": {"smoke": {"type": "grid", "file": "smoke.vdb", "sigma_a": [1, 1, 1]}},
      "shapes": [{"type": "sphere", "material": "boundary", "center": [0, 0, 0],
                  "radius": 0.5, "interior": "smoke"}],
      "lights": [{"type": "environment", "radiance": [1, 1, 1]}]})");
    const std::string plan = " plan " + scene + " --pilot-spp 2 --threads 1";
    const RunResult refused = RunCommand(alone + plan);
    EXPECT_NE(refused.status, 0) << refused.output;
    EXPECT_NE(refused.output.find("reading OpenVDB grids: no liblf_vdb.so of this build"),
              std::string::npos)
        << refused.output;
    for (const std::string& program : {std::string(LF_BIN_DIR) + "/lightfarm", installed}) {
        const RunResult read = RunCommand(program + plan);
        EXPECT_EQ(read.status, 0) << program << "\n" << read.output;
        EXPECT_NE(read.output.find("smoke.vdb#density 4x4x4"), std::string::npos) << program << "\n"
                                                                                  << read.output;
    }
}

TEST_F(Cli, PlanSaysWhatItWillModelAndWhatItCosts) {
    const RunResult r = Lightfarm("plan " + std::string(LF_TEST_SCENES) +
                                  "/cornell_box.json --pilot-spp 2 --target-error 0.5 --threads 2 "
                                  "--resolution 64x64");
    ASSERT_EQ(r.status, 0) << r.output;
    for (const char* text :
         {"light: lambert, reflectance (0, 0, 0), emits (17, 12, 4)", "2 emissive triangles",
          "method (--method auto): radiosity, because every material is Lambertian",
          "path depth: unlimited", "3936 patches", "cost of render --target-error 0.5"}) {
        EXPECT_NE(r.output.find(text), std::string::npos) << text << "\n" << r.output;
    }
    // The radiosity cost, from two pilot solves, for --method radiosity; refused where
    // radiosity cannot model the scene.
    const RunResult radiosity = Lightfarm("plan " + std::string(LF_TEST_SCENES) +
                                          "/cornell_box.json --method radiosity --patches 1000 "
                                          "--pilot-spp 2 --threads 2 --resolution 64x64");
    ASSERT_EQ(radiosity.status, 0) << radiosity.output;
    for (const char* text :
         {"method (--method radiosity): radiosity, because requested",
          "radiosity pilot: 242 patches", "radiosity pilot: 488 patches",
          "cost of render --method radiosity --radiosity flat --patches 1000: about",
          "s of form factors ("}) {
        EXPECT_NE(radiosity.output.find(text), std::string::npos) << text << "\n"
                                                                  << radiosity.output;
    }
    // Hierarchical pilots cost links; a flat target whose pilots alone would need gigabytes of
    // form factors is not piloted but bounded, and hierarchical is named.
    const RunResult links = Lightfarm("plan " + std::string(LF_TEST_SCENES) +
                                      "/cornell_box.json --method radiosity --radiosity "
                                      "hierarchical --patches 1000 --pilot-spp 2 --threads 2 "
                                      "--resolution 16x16");
    ASSERT_EQ(links.status, 0) << links.output;
    for (const char* text : {"radiosity (hierarchical): --patches 1000 ->",
                             "radiosity pilot: 242 patches", "unknowns: links ",
                             "cost of render --method radiosity --radiosity hierarchical "
                             "--patches 1000: about"}) {
        EXPECT_NE(links.output.find(text), std::string::npos) << text << "\n" << links.output;
    }
    const RunResult huge = Lightfarm("plan " + std::string(LF_TEST_SCENES) +
                                     "/cornell_box.json --method radiosity --patches 200000 "
                                     "--pilot-spp 2 --threads 2 --resolution 16x16");
    ASSERT_EQ(huge.status, 0) << huge.output;
    EXPECT_NE(huge.output.find("no radiosity pilot: the scene's triangles mesh to more than 8000 "
                               "unknowns"),
              std::string::npos)
        << huge.output;
    EXPECT_NE(huge.output.find("MiB of form factors (unknowns^2 floats at most); --radiosity "
                               "hierarchical grows about linearly instead"),
              std::string::npos)
        << huge.output;
    const RunResult refused = Lightfarm(
        "plan " + std::string(LF_TEST_SCENES) +
        "/khronos/AlphaBlendModeTest/AlphaBlendModeTest.gltf --camera auto --method radiosity "
        "--threads 2");
    EXPECT_NE(refused.status, 0);
    EXPECT_NE(refused.output.find("which radiosity does not model"), std::string::npos)
        << refused.output;
    // Every complete method costed from its own pilot, the path tracer named incomplete where a
    // point light's caustics are beyond it, and the fastest complete one named.
    const RunResult glossy = Lightfarm("plan " + std::string(LF_TEST_SCENES) +
                                       "/materials.json --pilot-spp 2 --threads 2 --photons 4096");
    ASSERT_EQ(glossy.status, 0) << glossy.output;
    for (const char* text :
         {"method (--method auto): bdpt, because caustics", "methods for --target-error 0.01",
          "\n  path ", "(incomplete: no caustics of the 1 point light)", "\n  bdpt ", "\n  ppm ",
          "fastest to the target by its pilot: "}) {
        EXPECT_NE(glossy.output.find(text), std::string::npos) << text << "\n" << glossy.output;
    }
    EXPECT_EQ(glossy.output.find("fastest to the target by its pilot: path"), std::string::npos)
        << glossy.output;
    EXPECT_EQ(glossy.output.find("\n  light "), std::string::npos) << "light sees no glass";
}

// A median rate below 0 (the error estimate rising between the pilot's stages, as on a 4x4
// Cornell box) was printed "spp^--0.81": the exponent is printed with its own sign.
TEST_F(Cli, PlanPrintsTheMeasuredExponentWithItsSign) {
    const RunResult r = Lightfarm("plan " + std::string(LF_TEST_SCENES) +
                                  "/cornell_box.json --method path --resolution 4x4 --threads 2 "
                                  "--photons 4096");
    ASSERT_EQ(r.status, 0) << r.output;
    // At 4x4 the estimate rises between the stages: a positive exponent, printed as such.
    const size_t at = r.output.find("error goes as spp^");
    ASSERT_NE(at, std::string::npos) << r.output;
    const char first = r.output[at + std::string("error goes as spp^").size()];
    EXPECT_TRUE(std::isdigit(static_cast<unsigned char>(first))) << r.output;
    EXPECT_EQ(r.output.find("spp^--"), std::string::npos) << r.output;
}

// A dielectric has an index of refraction and a conductor eta and k, not a reflectance: plan
// prints what each material's model uses.
TEST_F(Cli, PlanPrintsWhatEachMaterialUses) {
    const RunResult r = Lightfarm("plan " + std::string(LF_TEST_SCENES) +
                                  "/materials.json --pilot-spp 2 --threads 2");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("glass: dielectric, index of refraction 1.5\n"), std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("gold: glossy, conductor eta (0.143, 0.374"), std::string::npos)
        << r.output;
    EXPECT_EQ(r.output.find("glass: dielectric, reflectance"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("gold: glossy, reflectance"), std::string::npos) << r.output;
}

// -o writes OpenEXR (.exr) or the PNG preview (.png): any other name is refused before any
// work, by render and by fetch (which refuses before it asks a server).
TEST_F(Cli, OutputThatIsNeitherExrNorPngIsRefused) {
    const std::string scene = std::string(LF_TEST_SCENES) + "/cornell_box.json";
    const RunResult render =
        Lightfarm("render " + scene + " -o " + (dir_ / "out.tif").string() + " --spp 1");
    EXPECT_NE(render.status, 0);
    EXPECT_NE(render.output.find("-o " + (dir_ / "out.tif").string() +
                                 ": expected a name ending "
                                 "in .exr"),
              std::string::npos)
        << render.output;
    EXPECT_FALSE(fs::exists(dir_ / "out.tif"));
    const RunResult fetch =
        Lightfarm("fetch job-0 -o " + (dir_ / "out.tif").string() + " --server 127.0.0.1:1");
    EXPECT_NE(fetch.status, 0);
    EXPECT_NE(fetch.output.find("expected a name ending in .exr"), std::string::npos)
        << fetch.output;
    EXPECT_EQ(fetch.output.find("not reachable"), std::string::npos) << fetch.output;
    // A PNG -o is the preview already: --png beside it is refused, not silently a second copy.
    const RunResult twice = Lightfarm("render " + scene + " -o " + (dir_ / "a.png").string() +
                                      " --png " + (dir_ / "b.png").string() + " --spp 1");
    EXPECT_NE(twice.status, 0);
    EXPECT_NE(twice.output.find("--png"), std::string::npos) << twice.output;
}

// R,G,B of a PNG file, decoded by stb_image.
std::vector<int> DecodePng(const std::string& path) {
    int w = 0, h = 0, channels = 0;
    unsigned char* data = stbi_load(path.c_str(), &w, &h, &channels, 3);
    if (!data) return {};
    std::vector<int> out(data, data + size_t(w) * h * 3);
    stbi_image_free(data);
    return out;
}

// -o out.png writes the sRGB preview and nothing else (today's bytes: the clamped sRGB curve of
// the EXR's R,G,B), and --exposure scales only the PNG: the EXR of the same render keeps its
// bits, and the preview is the EXR's radiance times 2^EV, encoded.
TEST_F(Cli, PngOutputIsThePreviewAndExposureScalesOnlyIt) {
    const std::string scene = std::string(LF_TEST_SCENES) + "/cornell_box.json";
    const std::string common = " --spp 2 --seed 5 --resolution 24x24 --threads 2 --no-progress";
    const std::string only_png = (dir_ / "only" / "p.png").string();
    fs::create_directories(dir_ / "only");
    const RunResult png = Lightfarm("render " + scene + " -o " + only_png + common);
    ASSERT_EQ(png.status, 0) << png.output;
    EXPECT_NE(png.output.find("-> " + only_png), std::string::npos) << png.output;
    std::vector<std::string> written;
    for (const auto& entry : fs::directory_iterator(dir_ / "only")) {
        written.push_back(entry.path().filename().string());
    }
    EXPECT_EQ(written, std::vector<std::string>{"p.png"});

    const std::string exr = (dir_ / "e.exr").string(), bright = (dir_ / "bright.png").string();
    const RunResult r = Lightfarm("render " + scene + " -o " + exr + " --png " + bright +
                                  " --exposure 1.5" + common);
    ASSERT_EQ(r.status, 0) << r.output;
    absl::StatusOr<ExrFile> file = ReadExr(exr);
    ASSERT_TRUE(file.ok()) << file.status();
    const std::vector<int> plain = DecodePng(only_png), scaled = DecodePng(bright);
    ASSERT_EQ(plain.size(), size_t(24 * 24 * 3));
    ASSERT_EQ(scaled.size(), plain.size());
    int brighter = 0;
    for (int y = 0; y < 24; ++y) {
        for (int x = 0; x < 24; ++x) {
            const Rgb c = file->image.Pixel(x, y);
            for (int k = 0; k < 3; ++k) {
                const size_t i = (size_t(y) * 24 + x) * 3 + k;
                EXPECT_EQ(plain[i], EncodeSrgb8(c[k])) << x << "," << y;
                EXPECT_EQ(scaled[i], EncodeSrgb8(c[k] * float(std::exp2(1.5)))) << x << "," << y;
                brighter += scaled[i] > plain[i];
            }
        }
    }
    EXPECT_GT(brighter, 24 * 24);  // most of the image is lit
    // The EXR is never scaled: the same render without --exposure has the same bits.
    const std::string exr2 = (dir_ / "e2.exr").string();
    ASSERT_EQ(Lightfarm("render " + scene + " -o " + exr2 + common).status, 0);
    absl::StatusOr<ExrFile> file2 = ReadExr(exr2);
    ASSERT_TRUE(file2.ok()) << file2.status();
    EXPECT_EQ(*file->image.FindChannel("R"), *file2->image.FindChannel("R"));
}

// The flags of issue 13 refuse bad values at parse time, naming the flag, in render and in
// submit (before any server is asked).
TEST_F(Cli, BadAovClampFilterAndToneFlagsAreRefused) {
    const std::string scene = std::string(LF_TEST_SCENES) + "/cornell_box.json";
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"--aov albedo,shadow", "--aov albedo,shadow: unknown AOV \"shadow\""},
        {"--clamp -1", "--clamp -1: expected a radiance >= 0"},
        {"--clamp nan", "--clamp"},
        {"--filter lanczos", "--filter lanczos: unknown filter \"lanczos\""},
        {"--filter gaussian:wide", "--filter gaussian:wide: the width after ':'"},
        {"--filter gaussian:100", "--filter gaussian:100: width 100: expected 0.5 to 16"},
        {"--filter box:2", "--filter box:2: width 2: the box filter is one pixel wide"},
        {"--sampler halton", "--sampler halton: expected independent or sobol"},
        {"--light-sampling uniform", "--light-sampling uniform: expected power or bvh"},
    };
    for (const auto& [flags, message] : cases) {
        for (const std::string& command : {"render " + scene + " -o " + (dir_ / "x.exr").string(),
                                           "submit " + scene + " --server 127.0.0.1:1"}) {
            const RunResult r = Lightfarm(command + " --spp 1 " + flags);
            EXPECT_NE(r.status, 0) << command << " " << flags;
            EXPECT_NE(r.output.find(message), std::string::npos) << flags << ": " << r.output;
            EXPECT_EQ(r.output.find("not reachable"), std::string::npos) << r.output;
        }
    }
    for (const std::string flags : {"--tonemap aces", "--exposure 100"}) {
        const RunResult r =
            Lightfarm("render " + scene + " -o " + (dir_ / "x.exr").string() + " " + flags);
        EXPECT_NE(r.status, 0) << flags;
        EXPECT_NE(r.output.find(flags.substr(0, flags.find(' '))), std::string::npos) << r.output;
    }
    EXPECT_FALSE(fs::exists(dir_ / "x.exr"));
}

// --help explains the new flags: the clamp's bias, the filters and their default width, the
// AOV names, the tone curves and that exposure leaves the EXR alone.
TEST_F(Cli, HelpExplainsTheOutputFlags) {
    const RunResult r = Lightfarm("render --help");
    ASSERT_EQ(r.status, 0) << r.output;
    for (const char* text : {"--clamp", "Biased", "--filter", "blackman-harris", "default 3",
                             "--aov", "albedo", "depth", "--tonemap", "filmic", "--exposure",
                             "EXR is never scaled", ".png writes only"}) {
        EXPECT_NE(r.output.find(text), std::string::npos) << text;
    }
    // --method auto's rule as ChooseAutomatically applies it (path for media only it renders,
    // whitted, radiosity, bdpt, path), not the older radiosity-or-path rule.
    for (const char* text : {"auto (path for scattering, emitting or grid media",
                             "whitted where it is exact", "else bdpt for caustics"}) {
        EXPECT_NE(r.output.find(text), std::string::npos) << text;
    }
    EXPECT_EQ(r.output.find("there are no spheres"), std::string::npos);
    const RunResult submit = Lightfarm("submit --help");
    for (const char* text : {"--clamp", "--filter", "--aov"}) {
        EXPECT_NE(submit.output.find(text), std::string::npos) << text;
    }
    const RunResult fetch = Lightfarm("fetch --help");
    for (const char* text : {"--png", "--exposure", "--tonemap"}) {
        EXPECT_NE(fetch.output.find(text), std::string::npos) << text;
    }
}

// --clamp, --aov and --sampler go into the header (lightfarm.clamp, lightfarm.bias,
// lightfarm.aovs, lightfarm.sampler) and the summary says the error estimate leaves the clamp's
// bias out.
TEST_F(Cli, ClampAovsAndSamplerAreInTheHeader) {
    const std::string scene = std::string(LF_TEST_SCENES) + "/cornell_box.json";
    const std::string exr = (dir_ / "c.exr").string();
    const RunResult r = Lightfarm("render " + scene + " -o " + exr +
                                  " --spp 2 --resolution 16x16 --clamp 4 --aov normal,albedo "
                                  "--sampler independent --no-progress");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("noise only: --clamp biases the image"), std::string::npos) << r.output;
    absl::StatusOr<ExrFile> file = ReadExr(exr);
    ASSERT_TRUE(file.ok()) << file.status();
    const ExrAttributes& a = file->attributes;
    EXPECT_EQ(std::get<double>(a.at("lightfarm.clamp")), 4.0);
    EXPECT_NE(std::get<std::string>(a.at("lightfarm.bias")).find("biased"), std::string::npos);
    EXPECT_EQ(std::get<std::string>(a.at("lightfarm.aovs")), "albedo,normal");
    EXPECT_EQ(std::get<std::string>(a.at("lightfarm.sampler")), "independent");
    EXPECT_EQ(std::get<std::string>(a.at("lightfarm.filter")), "box");
    EXPECT_EQ(std::get<float>(a.at("whiteLuminance")), 683.0f);
    EXPECT_EQ(std::get<ExrChromaticities>(a.at("chromaticities")), kRec709Chromaticities);
}

// End to end (needs the sampling pipeline of issue 13: the loader's --filter, the film's AOV
// channels): --filter reaches the header through the loaded camera, and --aov all adds the AOV
// channels.
TEST_F(Cli, FilterAndAovChannelsReachTheImage) {
    const std::string scene = std::string(LF_TEST_SCENES) + "/cornell_box.json";
    const std::string exr = (dir_ / "f.exr").string();
    const RunResult r =
        Lightfarm("render " + scene + " -o " + exr +
                  " --spp 2 --resolution 16x16 --filter gaussian --aov all --no-progress");
    ASSERT_EQ(r.status, 0) << r.output;
    absl::StatusOr<ExrFile> file = ReadExr(exr);
    ASSERT_TRUE(file.ok()) << file.status();
    EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.filter")), "gaussian 3 px");
    for (const char* ch :
         {"albedo.R", "albedo.G", "albedo.B", "normal.X", "normal.Y", "normal.Z", "depth.Z"}) {
        EXPECT_NE(file->image.FindChannel(ch), nullptr) << ch;
    }
}

// --aov illuminance adds the illuminance channel in lux (the header says so), and --false-color
// lux writes out.falsecolor.png beside out.exr: the image's size plus the legend's rows. Without
// the AOV, --false-color lux is refused before anything renders, saying what to add.
TEST_F(Cli, FalseColorLuxWritesAPngWithALegendAndNeedsTheIlluminanceAov) {
    const std::string scene = std::string(LF_TEST_SCENES) + "/cornell_box.json";
    const std::string exr = (dir_ / "lux.exr").string();
    const std::string png = (dir_ / "lux.falsecolor.png").string();
    const RunResult r = Lightfarm("render " + scene + " -o " + exr +
                                  " --spp 2 --resolution 24x16 --aov illuminance --false-color "
                                  "lux --no-progress");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find(png), std::string::npos) << r.output;
    absl::StatusOr<ExrFile> file = ReadExr(exr);
    ASSERT_TRUE(file.ok()) << file.status();
    ASSERT_NE(file->image.FindChannel("illuminance"), nullptr);
    EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.aovs")), "illuminance");
    EXPECT_NE(
        std::get<std::string>(file->attributes.at("lightfarm.units")).find("illuminance: lux"),
        std::string::npos);
    int width = 0, height = 0, channels = 0;
    ASSERT_TRUE(stbi_info(png.c_str(), &width, &height, &channels)) << png;
    EXPECT_EQ(width, 24);
    EXPECT_EQ(height, 16 + kFalseColorLegendRows);

    const std::string refused_exr = (dir_ / "nolux.exr").string();
    const RunResult refused = Lightfarm("render " + scene + " -o " + refused_exr +
                                        " --spp 2 --resolution 24x16 --false-color lux "
                                        "--no-progress");
    EXPECT_NE(refused.status, 0);
    EXPECT_NE(refused.output.find("add --aov illuminance"), std::string::npos) << refused.output;
    EXPECT_EQ(refused.output.find("samples/s"), std::string::npos) << refused.output;
    EXPECT_FALSE(fs::exists(refused_exr));
    EXPECT_FALSE(fs::exists(dir_ / "nolux.falsecolor.png"));
    // A bad scale is refused by the flag itself.
    const RunResult bad = Lightfarm("render " + scene + " -o " + refused_exr +
                                    " --aov illuminance --false-color lux:100:1");
    EXPECT_NE(bad.status, 0);
    EXPECT_NE(bad.output.find("MIN < MAX"), std::string::npos) << bad.output;
}

TEST_F(Cli, BenchRefusesFewerThanOneThread) {
    const std::string scene = std::string(LF_TEST_SCENES) + "/cornell_box.json";
    for (const char* threads : {"0", "-1"}) {
        const RunResult r = Lightfarm("bench " + scene + " --threads " + threads);
        EXPECT_NE(r.status, 0) << threads;
        EXPECT_NE(r.output.find("--threads"), std::string::npos) << r.output;
    }
}

// A radiosity flag with --method path would be ignored: render and submit refuse it, naming the
// flag (submit before it contacts a server).
TEST_F(Cli, RadiosityFlagsWithMethodPathAreRefused) {
    const std::string scene = std::string(LF_TEST_SCENES) + "/cornell_box.json";
    const std::string exr = (dir_ / "p.exr").string();
    for (const std::string& command :
         {"render " + scene + " -o " + exr + " --spp 1 --no-progress",
          "submit " + scene + " --server 127.0.0.1:1 --retry-seconds 0"}) {
        for (const auto& [flags, named] :
             {std::pair{"--patches 300", "--patches"}, std::pair{"--solver shooting", "--solver"},
              std::pair{"--method path --tolerance 0.01", "--tolerance"}}) {
            const RunResult r = Lightfarm(command + " " + flags);
            EXPECT_NE(r.status, 0) << command << " " << flags;
            EXPECT_NE(r.output.find(std::string(named) + " is a radiosity setting"),
                      std::string::npos)
                << r.output;
        }
    }
    EXPECT_FALSE(fs::exists(exr));
}

// Every phase of a radiosity render is reported, and the header's seconds are the total.
TEST_F(Cli, RadiositySummaryReportsEveryPhaseAndTheTotal) {
    std::ifstream in(std::string(LF_TEST_SCENES) + "/cornell_box.json");
    nlohmann::json scene = nlohmann::json::parse(in);
    scene["camera"]["resolution"] = {32, 32};
    const std::string path = Write("cornell_32.json", scene.dump());
    const std::string exr = (dir_ / "r.exr").string();
    const RunResult r = Lightfarm("render " + path + " -o " + exr +
                                  " --method radiosity --patches 300 --spp 1 --no-progress");
    ASSERT_EQ(r.status, 0) << r.output;
    double load = -1, radiosity = -1, mesh = -1, ff = -1, solve = -1, render = -1, total = -1;
    const size_t at = r.output.find("time: ");
    ASSERT_NE(at, std::string::npos) << r.output;
    ASSERT_EQ(std::sscanf(r.output.c_str() + at,
                          "time: load %lf s, radiosity %lf s (mesh %lf s, form factors %lf s, "
                          "solve %lf s), render %lf s, total %lf s",
                          &load, &radiosity, &mesh, &ff, &solve, &render, &total),
              7)
        << r.output;
    // Each printed figure is its value rounded to 0.01 s, so within 0.005 of it: a sum of n
    // rounded parts against a rounded total may be off by 0.005 (n + 1).
    EXPECT_GE(radiosity, ff + solve - 0.015) << r.output;
    EXPECT_GE(total, load + radiosity + render - 0.02) << r.output;
    absl::StatusOr<ExrFile> file = ReadExr(exr);
    ASSERT_TRUE(file.ok()) << file.status();
    const double seconds = std::get<double>(file->attributes.at("lightfarm.seconds"));
    EXPECT_GE(seconds, load + radiosity + render - 0.015) << r.output;  // exact vs 3 rounded
    EXPECT_GE(seconds + 0.01,
              std::get<double>(file->attributes.at("lightfarm.radiosity.formFactorSeconds")) +
                  std::get<double>(file->attributes.at("lightfarm.radiosity.solveSeconds")));
}

// `render` and `submit` take their defaults from the job model: the same solver for both.
// Every command that samples an image takes --sampler, says what the two are, and defaults to
// Sobol; those that path trace one take --light-sampling likewise, defaulting to the light BVH.
TEST_F(Cli, HelpExplainsTheSamplerAndTheLightSampling) {
    const std::vector<const char*> sampler = {"--sampler independent|sobol", "low-discrepancy",
                                              "spp^-1/2", "for comparison", "Default sobol"};
    const std::vector<const char*> light = {"--light-sampling power|bvh", "light BVH",
                                            "solid angle", "proportional to its power",
                                            "Default bvh"};
    for (const std::string command : {"render", "submit", "bench", "converge", "plan"}) {
        const RunResult r = Lightfarm(command + " --help");
        ASSERT_EQ(r.status, 0) << r.output;
        // converge compares lists of light strategies (converge --compare) with its own flag.
        std::vector<const char*> texts = sampler;
        if (command != "converge") texts.insert(texts.end(), light.begin(), light.end());
        for (const char* text : texts) {
            EXPECT_NE(r.output.find(text), std::string::npos) << command << ": " << text << "\n"
                                                              << r.output;
        }
    }
}

// The mean radiance of an image and the variance of that mean, from each pixel's independent
// A/B halves: the mean of n samples is (A + B) / 2, and E[(A - B)^2] / 4 is its variance.
struct ImageMean {
    double mean = 0, variance = 0;
};
ImageMean MeanOfImage(const Image& image) {
    ImageMean m;
    const size_t n = image.FindChannel("R")->size();
    for (const char* c : {"R", "G", "B"}) {
        const std::vector<float>& a = *image.FindChannel(std::string("A.") + c);
        const std::vector<float>& b = *image.FindChannel(std::string("B.") + c);
        for (size_t i = 0; i < n; ++i) {
            m.mean += 0.5 * (double(a[i]) + b[i]) / double(n);
            m.variance += 0.25 * (double(a[i]) - b[i]) * (double(a[i]) - b[i]) / double(n * n);
        }
    }
    return m;
}

// --sky, without JSON: a Lambertian plane seen from above under a uniform sky of radiance L
// reflects rho / pi * pi L = rho L (the plane, open, sees only sky above it), so the image's mean
// over R, G and B is sum(rho) L. With a map lit (2) above the horizon and black below, read from
// outside the scene's folder, the same plane sees a uniform hemisphere of 2. Bad values are
// refused naming the flag and the value.
TEST_F(Cli, SkyFlagLightsTheSceneWithoutJson) {
    fs::create_directories(dir_ / "scene");
    fs::create_directories(dir_ / "maps");
    const std::string scene = Write("scene/plane.json", R"({
      "camera": {"position": [0, 2, 0.5], "look_at": [0, 0, 0], "fov_y_deg": 20,
                 "resolution": [8, 8]},
      "materials": {"m": {"type": "lambert", "reflectance": [0.5, 0.25, 0.75]}},
      "shapes": [{"type": "quad", "material": "m",
                  "vertices": [[-1000, 0, 1000], [1000, 0, 1000], [1000, 0, -1000],
                               [-1000, 0, -1000]]}]})");
    std::ofstream(dir_ / "maps" / "half.hdr", std::ios::binary)
        << testing::HdrBytes(2, 2, {2, 2, 2, 2, 2, 2, 0, 0, 0, 0, 0, 0});
    for (const auto& [sky, expected] : {std::pair<std::string, double>{"white", 1.5},
                                        {"2,2,2", 3.0},
                                        {(dir_ / "maps" / "half.hdr").string(), 3.0}}) {
        SCOPED_TRACE(sky);
        const std::string exr = (dir_ / "sky.exr").string();
        const RunResult r = Lightfarm("render " + scene + " -o " + exr + " --sky " + sky +
                                      " --spp 64 --seed 1 --no-progress");
        ASSERT_EQ(r.status, 0) << r.output;
        absl::StatusOr<ExrFile> file = ReadExr(exr);
        ASSERT_TRUE(file.ok()) << file.status();
        const ImageMean m = MeanOfImage(file->image);
        ASSERT_GT(m.variance, 0);
        EXPECT_LT(std::abs(m.mean - expected), 4 * std::sqrt(m.variance))
            << m.mean << " +- " << std::sqrt(m.variance);
        const std::string recorded = std::get<std::string>(file->attributes.at("lightfarm.sky"));
        EXPECT_EQ(recorded, sky.find('/') == std::string::npos ? sky : "../maps/half.hdr");
    }
    for (const auto& [sky, message] :
         {std::pair<std::string, std::string>{
              "1,2", "--sky \"1,2\": 2 numbers; expected white, R,G,B or a number"},
          {"-1", "--sky \"-1\": \"-1\" is not a radiance"},
          {"missing.hdr", "--sky missing.hdr: no such file"}}) {
        const RunResult r = Lightfarm("render " + scene + " -o " + (dir_ / "x.exr").string() +
                                      " --sky " + sky + " --no-progress");
        EXPECT_NE(r.status, 0) << r.output;
        EXPECT_NE(r.output.find(message), std::string::npos) << r.output;
    }
    // Replacing the scene's own sky is said.
    const std::string lit = Write("scene/lit.json", R"({
      "camera": {"position": [0, 2, 0.5], "look_at": [0, 0, 0], "fov_y_deg": 20,
                 "resolution": [4, 4]},
      "materials": {"m": {"type": "lambert", "reflectance": [0.5, 0.5, 0.5]}},
      "shapes": [{"type": "quad", "material": "m",
                  "vertices": [[-1, 0, 1], [1, 0, 1], [1, 0, -1], [-1, 0, -1]]}],
      "lights": [{"type": "environment", "radiance": 3}]})");
    const RunResult r = Lightfarm("render " + lit + " -o " + (dir_ / "lit.exr").string() +
                                  " --sky white --spp 2 --no-progress");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("--sky replaces the scene's environment light"), std::string::npos)
        << r.output;
}

// Ctrl-C during `render`: the process stops sampling, writes the whole passes done so far (each
// pixel the mean of its own samples, a whole number of 4-sample passes of its tile), says so in
// the header and on stderr, and exits with 130. The render would take minutes; SIGINT is sent
// once it logs that it samples (and again while it has not stopped: a Ctrl-C during loading ends
// it at once, which the status would show).
TEST_F(Cli, CtrlCWritesThePassesDoneSoFar) {
    const std::string exr = (dir_ / "partial.exr").string();
    const std::string log = (dir_ / "render.log").string();
    const std::string cmd = std::string(LF_BIN_DIR) + "/lightfarm render " +
                            std::string(LF_TEST_SCENES) + "/cornell_box.json -o " + exr +
                            " --resolution 32x32 --tile 16 --spp 262144 --passes 65536 "
                            "--threads 2 --no-progress";
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
        const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        dup2(fd, 1);
        dup2(fd, 2);
        execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), nullptr);
        _exit(127);
    }
    const auto read_log = [&] {
        std::ifstream in(log);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    int status = 0;
    bool sampling = false;
    for (int i = 0; i < 1200 && !sampling; ++i) {  // up to 2 minutes
        usleep(100'000);
        sampling = read_log().find(" rendering ") != std::string::npos;
    }
    ASSERT_TRUE(sampling) << read_log();
    usleep(500'000);  // past the log line, into the sampling
    kill(pid, SIGINT);
    ASSERT_EQ(waitpid(pid, &status, 0), pid);
    const std::string output = read_log();
    ASSERT_TRUE(WIFEXITED(status)) << "ended by signal " << WTERMSIG(status) << "\n" << output;
    EXPECT_EQ(WEXITSTATUS(status), 130) << output;
    EXPECT_NE(output.find("lightfarm: interrupted after "), std::string::npos) << output;
    EXPECT_NE(output.find("wrote it to " + exr), std::string::npos) << output;
    absl::StatusOr<ExrFile> file = ReadExr(exr);
    ASSERT_TRUE(file.ok()) << file.status();
    const std::string partial = std::get<std::string>(file->attributes.at("lightfarm.partial"));
    EXPECT_EQ(partial.rfind("interrupted after ", 0), 0u) << partial;
    EXPECT_EQ(file->attributes.count("lightfarm.estimatedError"), 0u);
    const std::vector<float>& spp = *file->image.FindChannel("spp");
    double samples = 0;
    for (float n : spp) {
        EXPECT_EQ(std::fmod(n, 4.0f), 0.0f);
        samples += n;
    }
    EXPECT_GT(samples, 0);
    EXPECT_LT(samples, 262144.0 * 32 * 32);
    for (const char* c : {"R", "G", "B"}) {
        for (float v : *file->image.FindChannel(c)) ASSERT_TRUE(std::isfinite(v)) << c;
    }
}

// --light-sampling reaches the path tracer: with the same seed, power and bvh give different
// bits, and the header and the log name each; both are unbiased, so bvh's mean with another
// seed (independent of power's) is power's within 4 standard errors of their difference.
TEST_F(Cli, LightSamplingReachesThePathTracerAndKeepsTheMean) {
    const std::string scene = std::string(LF_TEST_SCENES) + "/cornell_box.json";
    auto render = [&](const std::string& strategy, int seed) -> absl::StatusOr<ExrFile> {
        const std::string exr = (dir_ / (strategy + std::to_string(seed) + ".exr")).string();
        const RunResult r =
            Lightfarm("render " + scene + " -o " + exr + " --spp 16 --resolution 32x32 --seed " +
                      std::to_string(seed) + " --light-sampling " + strategy + " --no-progress");
        EXPECT_EQ(r.status, 0) << r.output;
        EXPECT_NE(r.output.find(strategy + " light sampling"), std::string::npos) << r.output;
        absl::StatusOr<ExrFile> file = ReadExr(exr);
        if (file.ok()) {
            EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.lightSampling")),
                      strategy);
        }
        return file;
    };
    const absl::StatusOr<ExrFile> power = render("power", 1), bvh = render("bvh", 1),
                                  bvh_other_seed = render("bvh", 2);
    ASSERT_TRUE(power.ok() && bvh.ok() && bvh_other_seed.ok());
    EXPECT_NE(*power->image.FindChannel("R"), *bvh->image.FindChannel("R"));
    const ImageMean p = MeanOfImage(power->image), b = MeanOfImage(bvh_other_seed->image);
    ASSERT_GT(p.variance, 0);
    ASSERT_GT(b.variance, 0);
    EXPECT_LT(std::abs(p.mean - b.mean), 4 * std::sqrt(p.variance + b.variance))
        << "power " << p.mean << " +- " << std::sqrt(p.variance) << ", bvh " << b.mean << " +- "
        << std::sqrt(b.variance);
}

TEST_F(Cli, RenderAndSubmitShareTheirDefaults) {
    for (const char* command : {"render --help", "submit --help"}) {
        const RunResult r = Lightfarm(command);
        ASSERT_EQ(r.status, 0) << r.output;
        for (const char* text : {"--solver TEXT:{jacobi,gauss-seidel,shooting}=jacobi",
                                 "--spp UINT:UINT in [1 - 16777216]=16", "--max-depth",
                                 "--max-spp UINT:UINT in [2 - 16777216]=65536",
                                 "--patches INT:INT in [1 - 16777216]=4000"}) {
            EXPECT_NE(r.output.find(text), std::string::npos) << command << ": " << text << "\n"
                                                              << r.output;
        }
    }
}

}  // namespace
}  // namespace lf

namespace lf {
namespace {

// `--method whitted` renders, logs what it leaves out of the scene and says so in the header;
// unknown methods are refused by render, submit and plan, naming the methods.
TEST_F(Cli, WhittedRendersAndUnknownMethodsAreRefused) {
    const std::string scene = std::string(LF_TEST_SCENES) + "/materials.json";
    const std::string exr = (dir_ / "w.exr").string();
    const RunResult r = Lightfarm("render " + scene + " -o " + exr +
                                  " --method whitted --spp 2 --threads 2 --no-progress");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("whitted leaves out"), std::string::npos) << r.output;
    absl::StatusOr<ExrFile> file = ReadExr(exr);
    ASSERT_TRUE(file.ok()) << file.status();
    EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.method")), "whitted");
    EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.lightSampling")), "bvh");

    for (const std::string& command :
         {"render " + scene + " -o " + exr, "submit " + scene, "plan " + scene}) {
        const RunResult unknown = Lightfarm(command + " --method photon");
        EXPECT_NE(unknown.status, 0);
        EXPECT_NE(unknown.output.find("expected one of"), std::string::npos) << unknown.output;
        EXPECT_NE(unknown.output.find("ppm"), std::string::npos) << unknown.output;
    }
}

// `render --method light` goes through the splat plan and merger: any --threads, --passes
// (light-path ranges) and --tile (splat tiles) give the same bits, and the header names the
// method and its light paths. Photon flags with another method, and AOVs and adaptive sampling
// with a splatting method, are refused, saying why.
TEST_F(Cli, LightTracingRendersTheSameBitsForAnySplit) {
    const std::string scene = std::string(LF_TEST_SCENES) + "/cornell_box.json";
    const std::string base = "render " + scene + " --method light --spp 2 --resolution 24x24 " +
                             "--max-depth 3 --no-progress -o ";
    const std::string one = (dir_ / "l1.exr").string(), two = (dir_ / "l2.exr").string();
    const RunResult a = Lightfarm(base + one + " --threads 1 --passes 1");
    ASSERT_EQ(a.status, 0) << a.output;
    const RunResult b = Lightfarm(base + two + " --threads 2 --passes 7 --tile 5");
    ASSERT_EQ(b.status, 0) << b.output;
    absl::StatusOr<ExrFile> fa = ReadExr(one), fb = ReadExr(two);
    ASSERT_TRUE(fa.ok() && fb.ok());
    ASSERT_EQ(fa->image.channels().size(), fb->image.channels().size());
    for (const auto& [name, values] : fa->image.channels()) {
        const std::vector<float>* other = fb->image.FindChannel(name);
        ASSERT_NE(other, nullptr) << name;
        EXPECT_EQ(values, *other) << name;
    }
    EXPECT_EQ(std::get<std::string>(fa->attributes.at("lightfarm.method")), "light");
    EXPECT_EQ(std::get<std::string>(fa->attributes.at("lightfarm.lightPaths")),
              std::to_string(2 * 24 * 24));
    double sum = 0;
    for (float v : *fa->image.FindChannel("G")) sum += v;
    EXPECT_GT(sum, 0) << "the lights reach the camera";

    const struct {
        std::string args, expected;
    } refused[] = {
        {"render " + scene + " -o " + one + " --photons 100", "--photons is a photon mapping"},
        {"render " + scene + " -o " + one + " --method light --aov albedo", "no AOV"},
        {"render " + scene + " -o " + one + " --method light --target-error 0.1", "adaptive"},
        {"render " + scene + " -o " + one + " --method ppm --ppm-alpha 1", "--ppm-alpha 1"},
    };
    for (const auto& r : refused) {
        const RunResult out = Lightfarm(r.args);
        EXPECT_NE(out.status, 0) << r.args;
        EXPECT_NE(out.output.find(r.expected), std::string::npos) << r.args << "\n" << out.output;
    }
}

// plan says what whitted would give whatever the method: exact where nothing of the
// scene's light is interreflected or focused (one lit plane), a preview with its missing terms
// named in the Cornell box; with --method whitted its pilot traces Whitted's rays.
TEST_F(Cli, PlanRecommendsWhittedOnlyAsAPreviewNamingWhatItLeavesOut) {
    const RunResult box =
        Lightfarm("plan " + std::string(LF_TEST_SCENES) +
                  "/cornell_box.json --pilot-spp 2 --threads 2 --resolution 64x64");
    ASSERT_EQ(box.status, 0) << box.output;
    for (const char* text : {"method (--method auto): radiosity",
                             "whitted: recommended only as a preview", "interreflection"}) {
        EXPECT_NE(box.output.find(text), std::string::npos) << text << "\n" << box.output;
    }
    const RunResult plane =
        Lightfarm("plan " +
                  Write("plane.json",
                        R"({"camera": {"position": [0, 3, 0], "look_at": [0, 0, 0], "up": [0, 0, 1],
                             "fov_y_deg": 60, "resolution": [16, 16]},
                  "materials": {"grey": {"type": "lambert", "reflectance": [0.5, 0.5, 0.5]}},
                  "shapes": [{"type": "quad", "material": "grey",
                              "vertices": [[-5, 0, -5], [-5, 0, 5], [5, 0, 5], [5, 0, -5]]}],
                  "lights": [{"type": "point", "position": [0, 2, 0], "power": [5, 5, 5]}]})") +
                  " --method whitted --pilot-spp 2 --threads 2");
    ASSERT_EQ(plane.status, 0) << plane.output;
    for (const char* text :
         {"method (--method whitted): whitted, because requested", "whitted: exact for this scene",
          "whitted depth: at most 8", "pilot (whitted ray tracing)"}) {
        EXPECT_NE(plane.output.find(text), std::string::npos) << text << "\n" << plane.output;
    }
}

// converge --method whitted: a spp ladder of Whitted images against the path-traced reference,
// with the light sampling named, and no path ladder.
TEST_F(Cli, ConvergeLaddersWhittedAgainstThePathTracedReference) {
    const fs::path out = dir_ / "conv_whitted";
    const std::string base = "converge " + std::string(LF_TEST_SCENES) + "/materials.json --out " +
                             out.string() + " --threads 2 ";
    const RunResult r = Lightfarm(base +
                                  "--resolution 16 --max-spp 4 --reference-spp 16 "
                                  "--method whitted");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("own path-traced reference, 16 spp"), std::string::npos) << r.output;
    const std::vector<std::vector<std::string>> rows = ReadCsv(out / "convergence.csv");
    ASSERT_EQ(rows.size(), 4u);  // the header; spp 1, 2, 4
    for (size_t i = 1; i < rows.size(); ++i) {
        ASSERT_EQ(rows[i].size(), 11u);
        EXPECT_EQ(rows[i][0], "whitted");
        EXPECT_EQ(rows[i][1], std::to_string(1 << (i - 1)));
        EXPECT_EQ(rows[i][8], "bvh");
    }
    EXPECT_GT(fs::file_size(out / "convergence.png"), 1000u);
}

// converge --method path,light,ppm: one ladder per method against one reference, named by the
// method in the CSV and the summary (the path tracer keeps its old name); the reference comes
// from an unbiased method that sees everything (path here: light tracing cannot see the glass).
TEST_F(Cli, ConvergeLaddersEveryListedMethod) {
    const fs::path out = dir_ / "conv_methods";
    const std::string base =
        "converge " + std::string(LF_TEST_SCENES) + "/materials.json --threads 2 --resolution 16 ";
    const RunResult r = Lightfarm(base + "--out " + out.string() +
                                  " --max-spp 8 --reference-spp 32 --method path,light,ppm "
                                  "--photons 2048");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("own path-traced reference, 32 spp"), std::string::npos) << r.output;
    const std::vector<std::vector<std::string>> rows = ReadCsv(out / "convergence.csv");
    ASSERT_EQ(rows.size(), 1u + 3 * 4);  // spp 1, 2, 4, 8 per method
    const std::vector<std::string> methods = {"path", "light", "ppm"};
    for (size_t m = 0; m < methods.size(); ++m) {
        for (size_t k = 0; k < 4; ++k) {
            const std::vector<std::string>& row = rows[1 + m * 4 + k];
            EXPECT_EQ(row[0], methods[m]);
            EXPECT_EQ(row[1], std::to_string(1 << k));
            EXPECT_GT(std::stod(row[3]), 0);
        }
    }
    for (const std::string name : {"sobol/bvh ", "light/sobol/bvh ", "ppm/sobol/bvh "}) {
        EXPECT_NE(r.output.find("\n" + name), std::string::npos) << name << "\n" << r.output;
    }
    const auto summary = ReadCsv(out / "summary.csv");
    ASSERT_EQ(summary.size(), 1u + 3);
    for (size_t m = 0; m < methods.size(); ++m) EXPECT_EQ(summary[1 + m].back(), methods[m]);

    for (const auto& [args, message] : std::vector<std::pair<std::string, std::string>>{
             {"--method path,foo", "--method path,foo: \"foo\" is not path, radiosity, both"},
             {"--method path,path", "\"path\" is listed twice"},
             {"--method path --photons 100", "--photons"},
             {"--method light --compare bdpt/sobol/bvh", "give the methods in one place"},
             {"--method path --ppm-alpha 1", "--ppm-alpha 1: expected above 0 and below 1"}}) {
        const RunResult refused = Lightfarm(base + "--out " + (dir_ / "bad").string() + " " + args);
        EXPECT_NE(refused.status, 0) << args;
        EXPECT_NE(refused.output.find(message), std::string::npos) << args << "\n"
                                                                   << refused.output;
    }
}

}  // namespace
}  // namespace lf
