// `lightfarm submit`: a scene and every file it reads, sent to lightfarm-server as a job.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "lf/client/adaptive_flags.h"
#include "lf/client/command.h"
#include "lf/client/farm_client.h"
#include "lf/client/farm_flags.h"
#include "lf/client/frame_flags.h"
#include "lf/client/method_flags.h"
#include "lf/client/photon_flags.h"
#include "lf/client/radiosity_flags.h"
#include "lf/client/sample_flags.h"
#include "lf/client/scene_flags.h"
#include "lf/core/file_util.h"
#include "lf/core/scene_loader.h"
#include "lf/job/digest.h"
#include "lf/job/job_spec.h"
#include "lf/job/plan.h"
#include "lf/job/scene_files.h"
#include "lf/job/worker_tags.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

// Loads the scene here, as `render` would, through a reader that records every file the loader
// reads by the name it asks for (the name the server and workers look it up by): exactly the
// files the farm needs (meshes, MTL files, included glTFs, their buffers and images), whatever
// the format. A scene that does not load is refused here, with the loader's message, before
// anything is uploaded. Returns the files' contents by name.
absl::StatusOr<std::map<std::string, std::string>> ReadSceneFiles(const fs::path& scene_path,
                                                                  const std::string& scene_text,
                                                                  const SceneOptions& options) {
    std::map<std::string, std::string> read;
    const fs::path parent = scene_path.parent_path();
    const SceneFileReader beside = ReadBeside(parent.empty() ? "." : parent.string());
    const SceneFileReader recording = [&](const std::string& name) {
        absl::StatusOr<std::string> bytes = beside(name);
        if (bytes.ok()) read[name] = *bytes;
        return bytes;
    };
    absl::StatusOr<Scene> scene = ParseScene(scene_text, scene_path.string(), recording, options);
    if (!scene.ok()) return scene.status();
    return read;
}

struct SubmitOptions {
    FarmFlags farm;
    bool watch = false;  // --watch: follow the job to its end, as `lightfarm watch`
    std::string scene_path;
    JobSpec spec;      // the scene and files are filled in by Submit
    std::string tags;  // --tags, into spec.tags
};

absl::StatusOr<std::string> Submit(const SubmitOptions& o, FarmClient& client) {
    const fs::path scene_path(o.scene_path);
    absl::StatusOr<std::string> scene_text = ReadFile(o.scene_path);
    // It exists (CLI::ExistingFile): say only that it cannot be read, as submit always has.
    if (!scene_text.ok()) return absl::NotFoundError(o.scene_path + ": cannot be read");
    absl::StatusOr<std::map<std::string, std::string>> read =
        ReadSceneFiles(scene_path, *scene_text, o.spec.scene_options);
    if (!read.ok()) return read.status();

    std::vector<BlobRef> refs;
    std::map<std::string, std::string> blobs;  // by hash
    auto add = [&](const std::string& name, std::string content) -> absl::Status {
        if (absl::Status s = CheckScenePath(name); !s.ok()) {
            return absl::InvalidArgumentError(absl::StrCat(o.scene_path, ": ", s.message()));
        }
        BlobRef ref{.path = name, .hash = Sha256Hex(content), .size = content.size()};
        blobs[ref.hash] = std::move(content);
        refs.push_back(std::move(ref));
        return absl::OkStatus();
    };
    if (absl::Status s = add(scene_path.filename().string(), *scene_text); !s.ok()) {
        return s;
    }
    for (auto& [name, content] : *read) {
        if (absl::Status s = add(name, std::move(content)); !s.ok()) return s;
    }

    JobSpec spec = o.spec;
    spec.scene = refs[0];
    spec.files.assign(refs.begin() + 1, refs.end());
    if (spec.name.empty()) spec.name = scene_path.filename().string();
    // The same id on every attempt: a retry after a lost answer (the server restarting, say)
    // gets the job of the first attempt.
    spec.request_id = Sha256Hex(
        absl::StrCat(absl::ToUnixNanos(absl::Now()), "/", ::getpid(), "/", scene_path.string()));
    return client.Submit(spec, blobs);
}

}  // namespace

Command AddSubmitCommand(CLI::App& app) {
    auto o = std::make_shared<SubmitOptions>();
    CLI::App* cmd = app.add_subcommand(
        "submit",
        "Send a scene to a lightfarm-server as a job and print its id (the last line).\n"
        "The scene file and every file it names (meshes; wherever `render` would find them)\n"
        "are uploaded, and the farm reads only those; files the\n"
        "server already has are not sent again. Same settings give the same bits as\n"
        "`lightfarm render`, whatever the tile size, passes or workers.");
    cmd->add_option("scene", o->scene_path, "scene file (JSON, .gltf or .glb)")
        ->required()
        ->check(CLI::ExistingFile);
    AddSceneFlags(cmd, o->spec.scene_options);
    AddSkyFlag(cmd, o->spec.scene_options);
    AddServerOption(cmd, o->farm);
    AddRetryOption(cmd, o->farm);
    cmd->add_flag("--watch", o->watch,
                  "after printing the job's id, follow it to its end as `lightfarm watch` does "
                  "(progress bar on a terminal, how it ended), with watch's exit status: 0 only "
                  "when it succeeded");
    auto frame_flags = std::make_shared<FrameFlags>();
    AddFrameFlags(cmd, *frame_flags);
    cmd->add_option("--spp", o->spec.plan.spp, "samples per pixel")
        ->capture_default_str()
        ->check(CLI::Range(uint64_t(1), kMaxSpp));
    cmd->add_option("--seed", o->spec.seed, "random seed")->capture_default_str();
    cmd->add_option("--max-depth", o->spec.max_depth,
                    "most bounces per path; -1 = unlimited (Russian roulette ends paths)")
        ->capture_default_str()
        ->check(CLI::Range(-1, kMaxDepthLimit));
    cmd->add_option("--tile", o->spec.plan.tile,
                    "tile side in pixels (a swept radiosity job's display tiles are widened to "
                    "2^18 samples a pass)")
        ->capture_default_str()
        ->check(CLI::Range(1, kMaxFarmTile));
    cmd->add_option("--passes", o->spec.plan.passes,
                    "sample passes per tile; each pass of each tile is one task")
        ->capture_default_str()
        ->check(CLI::Range(1, kMaxPasses));
    AddSampleFlags(cmd, o->spec.sampler, o->spec.light_strategy, o->spec.clamp, o->spec.aovs);
    AddAdaptiveFlags(cmd, o->spec.adaptive);
    cmd->add_option("--priority", o->spec.priority, "higher runs first; equal: oldest first")
        ->capture_default_str();
    cmd->add_option("--name", o->spec.name, "job name (default: the scene file's name)");
    cmd->add_option("--tags", o->tags,
                    "comma-separated tags (gpu,big-memory): only workers having every one take "
                    "the job (lightfarm-worker --tags); none: any worker")
        ->check([](const std::string& list) {
            const absl::StatusOr<std::vector<std::string>> parsed = ParseTags(list, "--tags");
            return parsed.ok() ? std::string() : std::string(parsed.status().message());
        });
    cmd->add_option("--max-workers", o->spec.max_workers,
                    "at most this many workers render the job at once; 0: no cap")
        ->capture_default_str()
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--after", o->spec.after,
                    "job ids, comma-separated or repeated: the job leases nothing until each has "
                    "succeeded, and fails when one fails or is cancelled")
        ->delimiter(',');
    // Job management (issue 30).
    cmd->add_option("--max-attempts", o->spec.max_attempts,
                    "failures of one task that fail the job (docs/farm.md, Managing jobs)")
        ->capture_default_str()
        ->check(CLI::Range(1, kMaxAttemptsLimit));
    cmd->add_option("--blocklist-after", o->spec.blocklist_after,
                    "a worker that fails this many of the job's tasks gets none of them any "
                    "more; the job fails when every live worker is blocklisted")
        ->capture_default_str()
        ->check(CLI::Range(1, kMaxAttemptsLimit));
    cmd->add_option(
           "--method", o->spec.method,
           "path, radiosity (Lambertian scenes; same bits as `lightfarm render "
           "--method radiosity` with the same options), whitted (direct light and "
           "specular chains only, a preview), or a splatting method: light (light tracing), "
           "bdpt (bidirectional path tracing), ppm (progressive photon mapping). Every "
           "method gives the bits of `lightfarm render` with the same options; the "
           "splatting methods take no --aov nor adaptive sampling")
        ->capture_default_str()
        ->check([](const std::string& m) { return MethodFlagError(m, false); });
    CLI::Option* chunk =
        cmd->add_option("--chunk", o->spec.shot.chunk,
                        "a shot's whole frames a task, each task rendering every tile of its "
                        "frames on one worker (fixed plans only: not with adaptive sampling "
                        "or sweeps: --solver jacobi, --radiosity hierarchical); 1: each frame's "
                        "tiles spread over the workers")
            ->capture_default_str()
            ->check(CLI::Range(1, kMaxChunk))
            ->group("Animation");
    AddPhotonFlags(cmd, o->spec.ppm);
    AddRadiosityFlags(cmd, o->spec.radiosity);
    cmd->add_option("--sweep-tasks", o->spec.radiosity.sweep_tasks,
                    "--solver jacobi or --radiosity hierarchical: chunks of the patch groups; "
                    "the first sweep is a task a chunk, and each worker computes the form-factor "
                    "rows (or links) of its chunks once and keeps them, so later sweeps are one "
                    "task a worker of all its chunks. Gauss-Seidel and "
                    "shooting update one group after another, so with them every worker "
                    "solves the whole system before rendering display tiles")
        ->group("Radiosity")
        ->capture_default_str()
        ->check(CLI::Range(1, kMaxSweepTasks));
    return {cmd, [cmd, o, chunk, frame_flags] {
                ApplyNoiseThresholdMinSpp(*cmd, o->spec.adaptive, o->spec.plan.spp);
                absl::StatusOr<ShotSettings> shot = ShotOfFrameFlags(*frame_flags);
                if (!shot.ok()) return ReportError(shot.status());
                shot->chunk = o->spec.shot.chunk;
                o->spec.shot = *shot;
                if (chunk->count() > 0 && !o->spec.shot.frames) {
                    return ReportError(absl::InvalidArgumentError(
                        absl::StrCat("--chunk ", o->spec.shot.chunk,
                                     ": whole frames a task needs a shot (--frames A-B)")));
                }
                if (absl::Status s = CheckRadiosityFlagsApply(*cmd, o->spec.method); !s.ok()) {
                    return ReportError(s);
                }
                if (absl::Status s = CheckPhotonFlagsApply(*cmd, o->spec.method); !s.ok()) {
                    return ReportError(s);
                }
                if (absl::Status s = ResolveSkyFile(o->scene_path, o->spec.scene_options);
                    !s.ok()) {
                    return ReportError(s);
                }
                o->spec.tags = *ParseTags(o->tags, "--tags");  // checked by the flag
                FarmClient client(o->farm);
                absl::StatusOr<std::string> id = Submit(*o, client);
                if (!id.ok()) return ReportError(id.status());
                std::printf("%s\n", id->c_str());
                if (!o->watch) return 0;
                std::fflush(stdout);  // the id first, for a script reading it as the job runs
                return WatchJob(client, *id);  // on the same connection
            }};
}

}  // namespace lf
