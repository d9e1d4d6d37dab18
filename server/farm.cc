#include "server/farm.h"

#include <unistd.h>

#include <atomic>
#include <filesystem>

#include "absl/strings/str_cat.h"
#include "lf/core/image_io.h"
#include "lf/core/log.h"
#include "lf/core/patch_mesh.h"
#include "lf/core/radiosity_codec.h"
#include "lf/core/tile_codec.h"
#include "lf/job/render_metadata.h"
#include "server/sqlite_job_store.h"

namespace lf {

namespace fs = std::filesystem;

namespace {

// Checked here so a bad job is refused at submission rather than failing on every worker.
absl::Status CheckMethod(const JobSpec& spec) {
    if (spec.method == "path") return absl::OkStatus();
    if (spec.method != "radiosity") {
        return absl::InvalidArgumentError(
            absl::StrCat("method \"", spec.method, "\": expected path or radiosity"));
    }
    const RadiositySettings& r = spec.radiosity;
    if (r.solver != "jacobi" && r.solver != "gauss-seidel" && r.solver != "shooting") {
        return absl::InvalidArgumentError(absl::StrCat(
            "radiosity solver \"", r.solver, "\": expected jacobi, gauss-seidel or shooting"));
    }
    if (r.display != "flat" && r.display != "smooth") {
        return absl::InvalidArgumentError(
            absl::StrCat("radiosity display \"", r.display, "\": expected flat or smooth"));
    }
    if (r.patches < 1 || !(r.patch_size >= 0) || !(r.tolerance > 0 && r.tolerance < 1) ||
        r.max_iterations < 1 || r.sweep_tasks < 1 || r.sweep_tasks > kMaxSweepTasks ||
        r.max_patches < 0 || r.max_patches > kMaxRefinedPatches) {
        return absl::InvalidArgumentError(absl::StrCat(
            "radiosity: patches and max iterations must be positive, patch size not negative, "
            "tolerance in (0, 1), sweep tasks in 1..",
            kMaxSweepTasks, ", max patches in 0..", kMaxRefinedPatches));
    }
    return absl::OkStatus();
}

absl::Status CheckRadiosityCanModel(const Scene& scene) {
    for (const Material& m : scene.materials) {
        if (m.type != Material::Type::kLambert) {
            return absl::InvalidArgumentError(absl::StrCat("radiosity: material \"", m.name,
                                                           "\" is ", MaterialTypeName(m.type),
                                                           "; radiosity models lambert only"));
        }
    }
    if (!scene.spheres.empty()) {
        return absl::InvalidArgumentError(absl::StrCat("radiosity: sphere '", scene.spheres[0].name,
                                                       "' cannot be meshed; radiosity supports "
                                                       "triangle meshes and quads only"));
    }
    return absl::OkStatus();
}

std::shared_ptr<spdlog::logger> Log() { return NamedLogger("farm"); }

// A name no other writer in this process uses at the same time.
std::string UniqueSuffix() {
    static std::atomic<uint64_t> counter{0};
    return absl::StrCat(::getpid(), "-", ++counter);
}

// The scheduler's options with each job's tiles in a file under the data folder's scratch/.
SchedulerOptions WithTileFiles(SchedulerOptions options, const std::string& data_dir) {
    options.tile_stores = [dir = data_dir + "/scratch"](std::vector<PixelRect> tiles) {
        return MakeFileTileStore(dir, std::move(tiles));
    };
    return options;
}

}  // namespace

absl::StatusOr<std::unique_ptr<Farm>> Farm::Open(const FarmOptions& options) {
    std::error_code ec;
    for (const char* sub : {"results", "previews", "scratch"}) {
        fs::create_directories(fs::path(options.data_dir) / sub, ec);
        if (ec) return absl::InternalError(options.data_dir + "/" + sub + ": " + ec.message());
    }
    absl::StatusOr<std::unique_ptr<BlobStore>> blobs = BlobStore::Open(options.data_dir + "/blobs");
    if (!blobs.ok()) return blobs.status();
    absl::StatusOr<std::unique_ptr<SqliteJobStore>> store =
        SqliteJobStore::Open(options.data_dir + "/jobs.db");
    if (!store.ok()) return store.status();
    std::unique_ptr<Farm> farm(new Farm(options, std::move(*blobs), std::move(*store)));
    absl::StatusOr<std::vector<std::string>> rendered = farm->scheduler_.Recover();
    if (!rendered.ok()) return rendered.status();
    for (const std::string& job_id : *rendered) farm->FinishJob(job_id);
    return farm;
}

Farm::Farm(const FarmOptions& options, std::unique_ptr<BlobStore> blobs,
           std::unique_ptr<JobStore> store)
    : options_(options),
      blobs_(std::move(blobs)),
      store_(std::move(store)),
      scheduler_(WithTileFiles(options.scheduler, options.data_dir), *store_) {}

absl::Status Farm::CheckSceneSize(uint64_t bytes) const {
    if (bytes <= options_.limits.max_scene_bytes) return absl::OkStatus();
    return absl::ResourceExhaustedError(
        absl::StrCat("the scene and its files are ", bytes, " bytes, above this server's limit of ",
                     options_.limits.max_scene_bytes, " (lightfarm-server --max-scene-mb)"));
}

absl::StatusOr<std::unique_ptr<BlobStore::Upload>> Farm::StartUpload(const std::string& hash,
                                                                     uint64_t size) {
    if (absl::Status s = CheckSceneSize(size); !s.ok()) return s;
    return blobs_->StartUpload(hash, size);
}

absl::StatusOr<std::string> Farm::Submit(JobSpec spec) {
    std::vector<const BlobRef*> refs = {&spec.scene};
    for (const BlobRef& f : spec.files) refs.push_back(&f);
    uint64_t scene_bytes = 0;
    for (const BlobRef* ref : refs) scene_bytes += ref->size;
    if (absl::Status s = CheckSceneSize(scene_bytes); !s.ok()) return s;
    if (spec.plan.spp > options_.limits.max_spp) {
        return absl::ResourceExhaustedError(
            absl::StrCat(spec.plan.spp, " samples per pixel is above this server's limit of ",
                         options_.limits.max_spp, " (lightfarm-server --max-spp)"));
    }
    for (const BlobRef* ref : refs) {
        if (absl::Status s = CheckScenePath(ref->path); !s.ok()) return s;
        if (!blobs_->Has(ref->hash)) {
            return absl::FailedPreconditionError(
                absl::StrCat(ref->path, ": blob ", ref->hash, " was not uploaded"));
        }
    }
    if (spec.plan.tile > kMaxFarmTile) {
        return absl::InvalidArgumentError(
            absl::StrCat("tile ", spec.plan.tile, " is above ", kMaxFarmTile,
                         ", the largest whose result fits one message"));
    }
    if (spec.max_depth < -1) {
        return absl::InvalidArgumentError(
            absl::StrCat("max depth ", spec.max_depth, " is below -1 (unlimited)"));
    }
    if (absl::Status s = CheckMethod(spec); !s.ok()) return s;
    if (absl::Status s = CheckAdaptiveSettings(spec.adaptive); !s.ok()) return s;
    if (IsAdaptive(spec.adaptive) && spec.adaptive.max_spp > options_.limits.max_spp) {
        return absl::ResourceExhaustedError(absl::StrCat(
            "adaptive sampling up to ", spec.adaptive.max_spp,
            " samples per pixel is above this server's limit of ", options_.limits.max_spp,
            " (lightfarm-server --max-spp); lower --max-spp"));
    }
    const std::string scratch = options_.data_dir + "/scratch/submit-" + UniqueSuffix();
    absl::StatusOr<Scene> scene = LoadSceneFromBlobs(
        spec.scene, spec.files, [&](const std::string& hash) { return blobs_->PathOf(hash); },
        scratch);
    if (!scene.ok()) {
        Log()->warn("submission of {} refused: {}", spec.scene.path,
                    std::string(scene.status().message()));
        return absl::InvalidArgumentError(scene.status().message());
    }
    if (spec.method == "radiosity") {
        if (absl::Status s = CheckRadiosityCanModel(*scene); !s.ok()) return s;
    }
    const int side = options_.limits.max_resolution;
    if (scene->camera.width > side || scene->camera.height > side) {
        return absl::ResourceExhaustedError(absl::StrCat("resolution ", scene->camera.width, "x",
                                                         scene->camera.height,
                                                         " is above this server's limit of ", side,
                                                         " pixels per side "
                                                         "(lightfarm-server --max-resolution)"));
    }
    spec.plan.width = scene->camera.width;
    spec.plan.height = scene->camera.height;
    spec.scene_hash = scene->content_hash;
    return scheduler_.Submit(spec);
}

absl::Status Farm::RefuseUndecodable(const std::string& lease_id, const std::string& worker,
                                     const absl::Status& why) {
    const std::string reason = absl::StrCat("undecodable result: ", why.message());
    scheduler_.Fail(lease_id, worker, reason, FailureKind::kTaskError).IgnoreError();
    return absl::InvalidArgumentError(
        absl::StrCat("lease ", lease_id, " from ", worker, ": ", reason));
}

absl::Status Farm::Complete(const std::string& lease_id, const std::string& worker,
                            std::string_view tile_sums) {
    absl::StatusOr<TileSums> sums = DecodeTileSums(tile_sums);
    if (!sums.ok()) return RefuseUndecodable(lease_id, worker, sums.status());
    absl::StatusOr<Scheduler::Completion> done = scheduler_.Complete(lease_id, worker, *sums);
    if (!done.ok()) return done.status();
    if (done->job_rendered) FinishJob(done->job_id);
    return absl::OkStatus();
}

absl::Status Farm::CompleteSweep(const std::string& lease_id, const std::string& worker,
                                 std::string_view sweep_result) {
    absl::StatusOr<SweepChunkResult> result = DecodeSweepResult(sweep_result);
    if (!result.ok()) return RefuseUndecodable(lease_id, worker, result.status());
    absl::StatusOr<Scheduler::SweepCompletion> done =
        scheduler_.CompleteSweep(lease_id, worker, *result);
    if (!done.ok()) return done.status();
    if (done->outcome) {
        scheduler_.Publish(done->job_id, done->outcome->converged,
                           blobs_->Put(EncodeRadiosity(done->outcome->radiosity)));
    }
    return absl::OkStatus();
}

absl::Status Farm::WriteSnapshot(const std::string& job_id, bool complete,
                                 const std::string& path) {
    std::lock_guard<std::mutex> lock(image_mutex_);
    absl::StatusOr<Scheduler::JobImage> snapshot = scheduler_.Snapshot(job_id);
    if (!snapshot.ok()) return snapshot.status();
    return WriteImage(*snapshot, complete, path);
}

void Farm::FinishJob(const std::string& job_id) {
    const std::string path = options_.data_dir + "/results/" + job_id + ".exr";
    const absl::Status written = WriteSnapshot(job_id, true, path);
    if (absl::IsFailedPrecondition(written)) return;  // cancelled meanwhile
    scheduler_.Finish(job_id, written.ok() ? absl::StatusOr<std::string>(path)
                                           : absl::StatusOr<std::string>(written));
}

void Farm::CheckTimers() {
    scheduler_.ExpireLeases();
    for (const std::string& job_id : scheduler_.EnforceTimeLimits()) FinishJob(job_id);
}

absl::Status Farm::WriteImage(const Scheduler::JobImage& snapshot, bool complete,
                              const std::string& path) {
    const JobRecord& job = snapshot.record;
    RenderMetadata metadata;
    metadata.scene_hash = job.spec.scene_hash;
    metadata.method = job.spec.method;
    metadata.spp = snapshot.adaptive ? snapshot.adaptive->max_spp : job.spec.plan.spp;
    metadata.seed = job.spec.seed;
    metadata.max_depth = job.spec.max_depth;
    metadata.seconds = job.started == absl::InfinitePast()
                           ? 0.0
                           : absl::ToDoubleSeconds(absl::Now() - job.started);
    metadata.stats = job.stats;
    // Renamed into place so a reader never sees half a file, and durable before the job is
    // recorded as succeeded.
    const std::string temp = path + ".tmp-" + UniqueSuffix();
    ExrAttributes attributes = DescribeRender(metadata);
    if (const uint64_t spp = snapshot.adaptive ? snapshot.adaptive->min_spp : job.spec.plan.spp;
        complete && spp >= 2) {
        if (absl::StatusOr<ErrorEstimates> e = AddErrorEstimates(snapshot.image, &attributes);
            !e.ok()) {
            return e.status();
        }
    }
    if (snapshot.adaptive) {
        AddAdaptiveAttributes(job.spec.adaptive, *snapshot.adaptive, &attributes);
    }
    if (absl::Status s = WriteExr(temp, snapshot.image, attributes); !s.ok()) return s;
    return RenameDurably(temp, path);
}

absl::StatusOr<std::string> Farm::ResultFile(const std::string& job_id, bool preview) {
    absl::StatusOr<JobRecord> job = scheduler_.Get(job_id);
    if (!job.ok()) return job.status();
    if (IsFinal(job->state)) {
        std::lock_guard<std::mutex> lock(image_mutex_);
        previewed_.erase(job_id);
    }
    if (job->state == JobState::kSucceeded) return job->result_path;
    if (!preview || IsFinal(job->state)) {
        return absl::FailedPreconditionError(absl::StrCat(
            "job ", job_id, " is ", JobStateName(job->state), " (", job->tasks_done, "/",
            job->tasks_total, " tasks done): no result",
            IsFinal(job->state) ? "" : " yet; --preview fetches what is merged so far"));
    }
    const std::string path = options_.data_dir + "/previews/" + job_id + ".exr";
    {
        std::lock_guard<std::mutex> lock(image_mutex_);
        auto it = previewed_.find(job_id);
        if (it != previewed_.end() && it->second == job->tasks_done) return path;
    }
    if (absl::Status s = WriteSnapshot(job_id, false, path); !s.ok()) return s;
    std::lock_guard<std::mutex> lock(image_mutex_);
    previewed_[job_id] = job->tasks_done;
    return path;
}

}  // namespace lf
