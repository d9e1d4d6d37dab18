#include "lf/job/shot_execution.h"

#include <algorithm>
#include <cstring>

#include "absl/strings/str_cat.h"
#include "lf/core/tile_codec.h"

namespace lf {

namespace {

// A shot's record: the parts of its result, each the frame's own record with the frame number.
struct RecordedPart {
    int frame = 0;
    std::string_view record;
};

void AppendBytes(std::string& out, const void* data, size_t size) {
    out.append(static_cast<const char*>(data), size);
}

std::string EncodeParts(const std::vector<std::pair<int, std::string>>& parts) {
    std::string out = "lfshot1";
    const uint32_t count = uint32_t(parts.size());
    AppendBytes(out, &count, sizeof count);
    for (const auto& [frame, record] : parts) {
        const int32_t f = frame;
        const uint64_t size = record.size();
        AppendBytes(out, &f, sizeof f);
        AppendBytes(out, &size, sizeof size);
        out += record;
    }
    return out;
}

absl::StatusOr<std::vector<RecordedPart>> DecodeParts(std::string_view in) {
    constexpr std::string_view kMagic = "lfshot1";
    const auto damaged = [](std::string_view why) {
        return absl::InvalidArgumentError(absl::StrCat("a shot task's record: ", std::string(why)));
    };
    if (in.substr(0, kMagic.size()) != kMagic) return damaged("not a shot record");
    in.remove_prefix(kMagic.size());
    const auto read = [&in](void* out, size_t size) {
        if (in.size() < size) return false;
        std::memcpy(out, in.data(), size);
        in.remove_prefix(size);
        return true;
    };
    uint32_t count = 0;
    if (!read(&count, sizeof count)) return damaged("truncated before its part count");
    // Each part takes at least 12 bytes: a count beyond that is damage, not an allocation.
    if (count > in.size() / 12)
        return damaged(absl::StrCat(count, " parts in ", in.size(), " bytes"));
    std::vector<RecordedPart> parts(count);
    for (RecordedPart& part : parts) {
        int32_t frame = 0;
        uint64_t size = 0;
        if (!read(&frame, sizeof frame) || !read(&size, sizeof size) || size > in.size()) {
            return damaged("truncated in a part");
        }
        part.frame = frame;
        part.record = in.substr(0, size_t(size));
        in.remove_prefix(size_t(size));
    }
    if (!in.empty()) return damaged(absl::StrCat(in.size(), " bytes after the last part"));
    return parts;
}

absl::Status WrongFrame(int got, int want) {
    return absl::InvalidArgumentError(
        absl::StrCat("the result of frame ", got, " for a task of frame ", want));
}

}  // namespace

absl::Status CheckShotChunk(const JobSpec& spec) {
    if (spec.shot.chunk <= 1) return absl::OkStatus();
    const auto refuse = [&](std::string_view why) {
        return absl::InvalidArgumentError(
            absl::StrCat("chunk ", spec.shot.chunk,
                         ": a task of several frames needs a plan fixed when the job "
                         "starts, and ",
                         std::string(why),
                         "; submit it with --chunk 1 (each frame's tasks spread over the "
                         "workers)"));
    };
    if (IsAdaptive(spec.adaptive)) {
        return refuse(
            "adaptive sampling (--target-error, --noise-threshold, --time-limit) adds passes as "
            "results merge");
    }
    if (SolvedInSweeps(spec)) return refuse("radiosity solved in sweeps adds a sweep at a time");
    // A chunk's result is one message and one record: every frame's sums (tile_codec.h: 104
    // bytes a pixel, up to 236 with AOVs) and, for splatting methods, up to 2 splats of 53 bytes a
    // pixel (the worker sums a frame's tasks' splats into one list). Each pass of a tile is a part
    // with the tile's sums.
    const uint64_t sums_bytes =
        EncodedTileSumsSize(1, spec.aovs) - EncodedTileSumsSize(0, spec.aovs);
    const uint64_t pixel_bytes = sums_bytes * uint64_t(std::max(spec.plan.passes, 1)) +
                                 (UsesSplatPlan(spec.method) ? 106 : 0);
    const uint64_t bytes = uint64_t(spec.shot.chunk) * uint64_t(spec.plan.width) *
                           uint64_t(spec.plan.height) * pixel_bytes;
    if (bytes > uint64_t(kMaxTaskResultBytes)) {
        return absl::InvalidArgumentError(
            absl::StrCat("chunk ", spec.shot.chunk, ": a task's result would take up to ", bytes,
                         " bytes (", spec.shot.chunk, " frames of ", spec.plan.width, "x",
                         spec.plan.height, "), above the coordinator's bound of ",
                         kMaxTaskResultBytes, " (lf::kMaxTaskResultBytes); use a smaller --chunk"));
    }
    return absl::OkStatus();
}

absl::StatusOr<std::unique_ptr<ShotExecution>> ShotExecution::Make(
    const JobSpec& spec, const TileStoreFactory& tile_stores) {
    if (!spec.shot.frames) return absl::InvalidArgumentError("a shot without frames");
    // Checked again: a spec read back from a damaged store has not been through CheckJobSettings,
    // and an empty range would leave no frame to plan.
    if (absl::Status s = CheckShotSettings(spec.shot); !s.ok()) return s;
    if (SolvedInSweeps(spec)) {
        // The coordinator stores and publishes one sweep's solution a job at a time.
        return absl::InvalidArgumentError(
            "radiosity --solver jacobi: the farm solves it in sweeps, one solve a job, not one a "
            "frame; render a shot with --solver gauss-seidel or shooting (each worker solves "
            "its frame)");
    }
    if (absl::Status s = CheckShotChunk(spec); !s.ok()) return s;
    const FrameRange& range = *spec.shot.frames;
    std::vector<std::unique_ptr<JobExecution>> frames;
    frames.reserve(size_t(range.count()));
    for (int i = 0; i < range.count(); ++i) {
        absl::StatusOr<std::unique_ptr<JobExecution>> frame =
            MakeFrameExecution(FrameSpec(spec, range.at(i)), tile_stores);
        if (!frame.ok()) return frame.status();
        frames.push_back(std::move(*frame));
        // Every frame plans as the first: bounded before the others are made.
        const int64_t tasks = int64_t(frames.front()->task_count()) * range.count();
        if (i == 0 && tasks > kMaxShotTasks) {
            return absl::InvalidArgumentError(absl::StrCat(
                "frames ", FrameRangeText(range), ": ", range.count(), " frames of ",
                frames.front()->task_count(), " tasks each is ", tasks,
                " tasks, above the coordinator's bound of ", kMaxShotTasks,
                " (lf::kMaxShotTasks); use a larger --tile, fewer --passes or fewer frames a job"));
        }
    }
    return std::unique_ptr<ShotExecution>(new ShotExecution(spec, std::move(frames)));
}

ShotExecution::ShotExecution(const JobSpec& spec, std::vector<std::unique_ptr<JobExecution>> frames)
    : frames_(*spec.shot.frames),
      chunk_(spec.shot.chunk),
      width_(spec.plan.width),
      height_(spec.plan.height),
      spp_(spec.plan.spp),
      frames_exec_(std::move(frames)) {
    if (chunk_ > 1) {
        const int chunks = (frames_.count() + chunk_ - 1) / chunk_;
        for (int c = 0; c < chunks; ++c) parts_merged_.emplace_back(PartsOf(c).size(), false);
        return;
    }
    shot_index_.resize(frames_exec_.size());
    for (int i = 0; i < int(frames_exec_.size()); ++i) Index(i);
}

void ShotExecution::Index(int index) {
    std::vector<int>& indices = shot_index_[size_t(index)];
    for (int t = int(indices.size()); t < int(frames_exec_[size_t(index)]->task_count()); ++t) {
        indices.push_back(int(located_.size()));
        located_.emplace_back(index, t);
    }
}

std::pair<int, int> ShotExecution::FramesOfChunk(int c) const {
    return {c * chunk_, std::min((c + 1) * chunk_, frames_.count())};
}

std::vector<std::pair<int, int>> ShotExecution::PartsOf(int c) const {
    std::vector<std::pair<int, int>> parts;
    const auto [begin, end] = FramesOfChunk(c);
    for (int i = begin; i < end; ++i) {
        for (int t = 0; t < int(frames_exec_[size_t(i)]->task_count()); ++t)
            parts.emplace_back(i, t);
    }
    return parts;
}

size_t ShotExecution::task_count() const {
    return chunk_ > 1 ? parts_merged_.size() : located_.size();
}

int ShotExecution::tasks_total() const {
    if (chunk_ > 1) return int(parts_merged_.size());
    int total = 0;
    for (const auto& frame : frames_exec_) total += frame->tasks_total();
    return total;
}

size_t ShotExecution::tasks_done() const {
    size_t done = 0;
    if (chunk_ > 1) {
        for (const std::vector<bool>& merged : parts_merged_) {
            done += std::all_of(merged.begin(), merged.end(), [](bool m) { return m; });
        }
        return done;
    }
    for (const auto& frame : frames_exec_) done += frame->tasks_done();
    return done;
}

bool ShotExecution::Complete() const {
    return std::all_of(frames_exec_.begin(), frames_exec_.end(),
                       [](const auto& frame) { return frame->Complete(); });
}

int ShotExecution::frames_done() const {
    return int(std::count_if(frames_exec_.begin(), frames_exec_.end(),
                             [](const auto& frame) { return frame->Complete(); }));
}

const RenderStats& ShotExecution::stats() const {
    stats_ = {};
    for (const auto& frame : frames_exec_) stats_ += frame->stats();
    return stats_;
}

std::string ShotExecution::Summary() const {
    std::string summary = absl::StrCat("frames ", FrameRangeText(frames_), " (", frames_.count(),
                                       " frames, each ", frames_exec_.front()->Summary(), ")");
    if (chunk_ > 1) absl::StrAppend(&summary, ", ", task_count(), " tasks of ", chunk_, " frames");
    return summary;
}

std::vector<int> ShotExecution::Start() {
    std::vector<int> ready;
    for (int i = 0; i < int(frames_exec_.size()); ++i) {
        const std::vector<int> started = frames_exec_[size_t(i)]->Start();
        if (chunk_ > 1) continue;
        Index(i);
        for (int t : started) ready.push_back(shot_index_[size_t(i)][size_t(t)]);
    }
    if (chunk_ > 1) {
        for (int c = 0; c < int(task_count()); ++c) ready.push_back(c);
    }
    return ready;
}

std::pair<int, int> ShotExecution::Locate(int task) const {
    if (chunk_ > 1) return {task * chunk_, 0};
    return located_[size_t(task)];
}

std::vector<int> ShotExecution::FramesOf(int task) const {
    if (chunk_ <= 1) return {frames_.at(Locate(task).first)};
    std::vector<int> frames;
    const auto [begin, end] = FramesOfChunk(task);
    for (int i = begin; i < end; ++i) frames.push_back(frames_.at(i));
    return frames;
}

uint64_t ShotExecution::QueueRank(int task) const {
    // Frame by frame, so that frames finish in order; within a frame, the frame's own order.
    const auto [index, t] = Locate(task);
    constexpr uint64_t kFrameRank = uint64_t(1) << 40;
    const uint64_t within = chunk_ > 1 ? 0 : frames_exec_[size_t(index)]->QueueRank(t);
    return uint64_t(index) * kFrameRank + std::min(within, kFrameRank - 1);
}

void ShotExecution::Lease(int task, const std::string& worker, TaskAssignment& lease) {
    if (chunk_ <= 1) {
        const auto [index, t] = Locate(task);
        frames_exec_[size_t(index)]->Lease(t, worker, lease);
        lease.task.index = task;  // the shot's index, not the frame's own
        lease.frame = frames_.at(index);
        return;
    }
    lease.parts.clear();
    lease.task.index = task;
    for (const auto& [index, t] : PartsOf(task)) {
        TaskAssignment part;
        frames_exec_[size_t(index)]->Lease(t, worker, part);
        lease.parts.push_back({frames_.at(index), part.task, part.path_begin, part.path_end});
    }
}

std::string ShotExecution::PreferredWorker(int task) const {
    if (chunk_ > 1) return "";
    const auto [index, t] = Locate(task);
    return frames_exec_[size_t(index)]->PreferredWorker(t);
}

void ShotExecution::Describe(int task, TaskStatus& status) const {
    const auto [index, t] = Locate(task);
    frames_exec_[size_t(index)]->Describe(t, status);
    status.frames = FramesOf(task);
    if (chunk_ > 1) {  // whole frames
        status.x = status.y = 0;
        status.width = width_;
        status.height = height_;
        status.samples = spp_;
    }
}

uint64_t ShotExecution::TaskSamples(int task) const {
    if (chunk_ <= 1) {
        const auto [index, t] = Locate(task);
        return frames_exec_[size_t(index)]->TaskSamples(t);
    }
    uint64_t samples = 0;
    for (const auto& [index, t] : PartsOf(task))
        samples += frames_exec_[size_t(index)]->TaskSamples(t);
    return samples;
}

size_t ShotExecution::ResultParts(int task) const { return chunk_ > 1 ? PartsOf(task).size() : 0; }

absl::StatusOr<std::vector<int>> ShotExecution::MergePart(int index, int task,
                                                          const TaskResult& part) {
    absl::StatusOr<Merged> merged = frames_exec_[size_t(index)]->Merge(task, part);
    if (!merged.ok()) return merged.status();
    if (!merged->job_error.ok()) return merged->job_error;
    return std::move(merged->appended);
}

absl::StatusOr<JobExecution::Merged> ShotExecution::Merge(int task, const TaskResult& result) {
    const std::vector<bool> complete_before = [&] {
        std::vector<bool> complete;
        for (const auto& frame : frames_exec_) complete.push_back(frame->Complete());
        return complete;
    }();
    Merged merged;
    if (chunk_ <= 1) {
        const auto [index, t] = Locate(task);
        if (!result.parts.empty()) {
            return absl::InvalidArgumentError("a chunk's parts in the result of one frame's task");
        }
        if (!result.frame)
            return absl::InvalidArgumentError("a shot task's result without its frame");
        if (*result.frame != frames_.at(index)) return WrongFrame(*result.frame, frames_.at(index));
        absl::StatusOr<Merged> inner = frames_exec_[size_t(index)]->Merge(t, result);
        if (!inner.ok()) return inner.status();
        merged = std::move(*inner);
        Index(index);
        for (int& appended : merged.appended) {
            appended = shot_index_[size_t(index)][size_t(appended)];
        }
    } else {
        const std::vector<std::pair<int, int>> parts = PartsOf(task);
        if (result.parts.size() != parts.size()) {
            return absl::InvalidArgumentError(absl::StrCat(
                result.parts.size(), " parts in the result of a chunk of ", parts.size()));
        }
        std::vector<bool>& done = parts_merged_[size_t(task)];
        // Whole before any part merges: a part merged before (a result refused half way) is
        // not merged again, but recorded with the rest (RecordOf), so it must be whole too.
        for (size_t k = 0; k < parts.size(); ++k) {
            const int want = frames_.at(parts[k].first);
            const TaskResult& part = result.parts[k];
            if (part.frame != want) return WrongFrame(part.frame.value_or(0), want);
            if (done[k] && !frames_exec_.front()->RecordOf(part)) {
                return absl::InvalidArgumentError(absl::StrCat(
                    "part ", k, " (frame ", want, ") of a chunk's result without its sums"));
            }
        }
        for (size_t k = 0; k < parts.size(); ++k) {
            if (done[k]) continue;
            const auto [index, t] = parts[k];
            const TaskResult& part = result.parts[k];
            absl::StatusOr<std::vector<int>> appended = MergePart(index, t, part);
            if (!appended.ok()) {
                return absl::Status(
                    appended.status().code(),
                    absl::StrCat("part ", k, " (frame ", frames_.at(index), ", its task ", t,
                                 "): ", appended.status().message()));
            }
            done[k] = true;
        }
    }
    for (int i = 0; i < int(frames_exec_.size()); ++i) {
        if (!complete_before[size_t(i)] && frames_exec_[size_t(i)]->Complete()) {
            merged.frames_completed.push_back(frames_.at(i));
        }
    }
    return merged;
}

std::optional<std::string> ShotExecution::RecordOf(const TaskResult& result) const {
    std::vector<std::pair<int, std::string>> parts;
    const auto add = [&](const TaskResult& part) {
        std::optional<std::string> record = frames_exec_.front()->RecordOf(part);
        if (!record) return false;
        parts.emplace_back(part.frame.value_or(0), std::move(*record));
        return true;
    };
    if (chunk_ <= 1) {
        if (!add(result)) return std::nullopt;
    } else {
        for (const TaskResult& part : result.parts) {
            if (!add(part)) return std::nullopt;
        }
    }
    return EncodeParts(parts);
}

absl::StatusOr<std::vector<int>> ShotExecution::MergeRecorded(int task, std::string_view record) {
    // A store's index the plan has not made (yet): damage, or results replayed out of order.
    if (task < 0 || size_t(task) >= task_count()) {
        return absl::InvalidArgumentError(
            absl::StrCat("a record of task ", task, " of a shot planned with ", task_count()));
    }
    absl::StatusOr<std::vector<RecordedPart>> recorded = DecodeParts(record);
    if (!recorded.ok()) return recorded.status();
    const std::vector<std::pair<int, int>> parts =
        chunk_ > 1 ? PartsOf(task) : std::vector<std::pair<int, int>>{Locate(task)};
    if (recorded->size() != parts.size()) {
        return absl::InvalidArgumentError(absl::StrCat("a shot task's record of ", recorded->size(),
                                                       " parts for a task of ", parts.size()));
    }
    std::vector<int> appended;
    for (size_t k = 0; k < parts.size(); ++k) {
        const auto [index, t] = parts[k];
        if ((*recorded)[k].frame != frames_.at(index)) {
            return WrongFrame((*recorded)[k].frame, frames_.at(index));
        }
        if (chunk_ > 1 && parts_merged_[size_t(task)][k]) continue;
        absl::StatusOr<std::vector<int>> more =
            frames_exec_[size_t(index)]->MergeRecorded(t, (*recorded)[k].record);
        if (!more.ok()) return more.status();
        if (chunk_ > 1) {
            parts_merged_[size_t(task)][k] = true;
            continue;
        }
        Index(index);
        for (int a : *more) appended.push_back(shot_index_[size_t(index)][size_t(a)]);
    }
    return appended;
}

std::optional<std::vector<int>> ShotExecution::EnforceTimeLimit(absl::Time started,
                                                                absl::Time now) {
    // The limit is the shot's (from the job's start); only adaptive frames have one, never chunked.
    std::optional<std::vector<int>> dropped;
    for (int i = 0; i < int(frames_exec_.size()); ++i) {
        std::optional<std::vector<int>> frame =
            frames_exec_[size_t(i)]->EnforceTimeLimit(started, now);
        if (!frame) continue;
        if (!dropped) dropped.emplace();
        for (int t : *frame) dropped->push_back(shot_index_[size_t(i)][size_t(t)]);
    }
    return dropped;
}

std::optional<absl::Duration> ShotExecution::time_limit() const {
    return frames_exec_.front()->time_limit();
}

void ShotExecution::AddBlobsInUse(std::set<std::string>& hashes) const {
    for (const auto& frame : frames_exec_) frame->AddBlobsInUse(hashes);
}

JobExecution::ImageReader ShotExecution::SnapshotReader() const {
    for (const auto& frame : frames_exec_) {
        if (!frame->Complete()) return frame->SnapshotReader();
    }
    return frames_exec_.back()->SnapshotReader();
}

std::vector<FrameProgress> ShotExecution::Frames() const {
    std::vector<FrameProgress> frames;
    for (int i = 0; i < int(frames_exec_.size()); ++i) {
        const JobExecution& frame = *frames_exec_[size_t(i)];
        frames.push_back({.frame = frames_.at(i),
                          .tasks_done = int(frame.tasks_done()),
                          .tasks_total = frame.tasks_total(),
                          .done = frame.Complete()});
    }
    return frames;
}

const JobExecution* ShotExecution::FrameExecution(int frame) const {
    if (!frames_.Contains(frame)) return nullptr;
    return frames_exec_[size_t(frames_.IndexOf(frame))].get();
}

}  // namespace lf
