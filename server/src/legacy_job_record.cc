#include "lf/server/legacy_job_record.h"

#include <nlohmann/json.hpp>
#include <stdexcept>

#include "absl/strings/str_cat.h"
#include "lf/core/pixel_filter.h"

namespace lf {

namespace {

using nlohmann::json;

// An integer field. nlohmann's get<T> casts a floating-point number to T, which is undefined
// beyond T's range: a fuzzed record whose seq was 1e111 found it (tests/fuzz/regressions).
template <typename T>
T Integer(const json& j) {
    if (!j.is_number_integer()) throw std::invalid_argument("an integer was expected");
    return j.get<T>();
}

template <typename T>
T IntegerOr(const json& j, const char* key, T otherwise) {
    return j.contains(key) ? Integer<T>(j.at(key)) : otherwise;
}


// Times as Unix microseconds; absl::InfinitePast (not yet) as null.
absl::Time TimeFromJson(const json& j) {
    return j.is_null() ? absl::InfinitePast() : absl::FromUnixMicros(Integer<int64_t>(j));
}

BlobRef BlobFromJson(const json& j) {
    return {j.at("path").get<std::string>(), j.at("hash").get<std::string>(),
            Integer<uint64_t>(j.at("size"))};
}

// `--filter` as {"type": name, "width": pixels}, or null for the scene's own.
absl::StatusOr<std::optional<PixelFilter>> FilterFromJson(const json& j) {
    if (j.is_null()) return std::nullopt;
    const std::string name = j.at("type").get<std::string>();
    const std::optional<PixelFilter::Type> type = PixelFilterTypeFromName(name);
    if (!type) {
        return absl::DataLossError(
            absl::StrCat("the stored record's filter \"", name, "\" is not a pixel filter"));
    }
    return PixelFilter{*type, j.at("width").get<double>()};
}

// A name; or, in records written before states were stored by name, the enum's position then.
absl::StatusOr<JobState> StateFromJson(const json& j) {
    if (j.is_string()) return JobStateFromName(j.get<std::string>());
    const int legacy = Integer<int>(j);
    if (legacy < int(JobState::kQueued) || legacy > int(JobState::kCancelled)) {
        return absl::InvalidArgumentError(absl::StrCat("unknown job state ", legacy));
    }
    return JobState(legacy);
}

}  // namespace

absl::StatusOr<JobRecord> DecodeLegacyJobRecord(std::string_view text) {
    try {
        const json j = json::parse(text);
        JobRecord r;
        r.id = j.at("id").get<std::string>();
        r.seq = Integer<uint64_t>(j.at("seq"));
        const json& s = j.at("spec");
        r.spec.name = s.at("name").get<std::string>();
        r.spec.scene = BlobFromJson(s.at("scene"));
        for (const json& f : s.at("files")) r.spec.files.push_back(BlobFromJson(f));
        r.spec.plan.width = Integer<int>(s.at("width"));
        r.spec.plan.height = Integer<int>(s.at("height"));
        r.spec.plan.spp = Integer<uint64_t>(s.at("spp"));
        r.spec.plan.tile = Integer<int>(s.at("tile"));
        r.spec.plan.passes = Integer<int>(s.at("passes"));
        r.spec.seed = Integer<uint64_t>(s.at("seed"));
        r.spec.max_depth = Integer<int>(s.at("max_depth"));
        r.spec.method = s.value("method", "path");
        if (s.contains("radiosity")) {
            const auto& rad = s.at("radiosity");
            r.spec.radiosity = {Integer<int64_t>(rad.at("patches")),
                                rad.at("patch_size").get<double>(),
                                rad.at("solver").get<std::string>(),
                                rad.at("tolerance").get<double>(),
                                Integer<int>(rad.at("max_iterations")),
                                rad.at("display").get<std::string>(),
                                IntegerOr(rad, "sweep_tasks", RadiositySettings().sweep_tasks),
                                IntegerOr(rad, "max_patches", int64_t(0))};
        }
        if (s.contains("adaptive")) {
            const auto& a = s.at("adaptive");
            r.spec.adaptive = {a.at("target_error").get<double>(), a.at("time_limit").get<double>(),
                               Integer<uint64_t>(a.at("max_spp"))};
        }
        // Records before --camera and --resolution have neither: the scene's own view.
        r.spec.scene_options.camera = s.value("camera", std::string());
        if (s.contains("resolution")) {
            r.spec.scene_options.width = Integer<int>(s.at("resolution").at(0));
            r.spec.scene_options.height = Integer<int>(s.at("resolution").at(1));
        }
        // Records before --filter, --clamp and --aov have none of them: off.
        if (s.contains("filter")) {
            absl::StatusOr<std::optional<PixelFilter>> filter = FilterFromJson(s.at("filter"));
            if (!filter.ok()) return filter.status();
            r.spec.scene_options.filter = *filter;
        }
        // Records before --method ppm have no photon settings: the defaults.
        if (s.contains("ppm")) {
            const auto& p = s.at("ppm");
            r.spec.ppm = {Integer<uint64_t>(p.at("photons_per_pass")),
                          p.at("initial_radius").get<double>(), p.at("alpha").get<double>()};
        }
        r.spec.clamp = s.value("clamp", 0.0);
        r.spec.aovs = IntegerOr(s, "aovs", uint32_t(0));
        // Records before --sampler were rendered with independent numbers; a job resumed from
        // one must keep them, or its remaining tiles would not match those already merged.
        const std::string sampler = s.value("sampler", "independent");
        if (const std::optional<SamplerType> type = SamplerTypeFromName(sampler)) {
            r.spec.sampler = *type;
        } else {
            return absl::DataLossError(
                absl::StrCat("the stored record's sampler \"", sampler, "\" is not a sampler"));
        }
        // Records before --light-sampling were rendered picking lights by power; resumed, they must
        // keep it, or their remaining tiles would not match those already merged.
        const std::string light = s.value("light_strategy", "power");
        if (const std::optional<LightStrategy> strategy = LightStrategyFromName(light)) {
            r.spec.light_strategy = *strategy;
        } else {
            return absl::DataLossError(absl::StrCat("the stored record's light_strategy \"", light,
                                                    "\" is not power or bvh"));
        }
        r.spec.priority = Integer<int>(s.at("priority"));
        r.spec.scene_hash = s.at("scene_hash").get<std::string>();
        r.spec.request_id = s.value("request_id", "");
        r.spec.owner = s.value("owner", "");
        if (absl::StatusOr<JobState> state = StateFromJson(j.at("state")); state.ok()) {
            r.state = *state;
        } else {
            return absl::DataLossError(
                absl::StrCat("the stored record's state: ", state.status().message()));
        }
        r.error = j.at("error").get<std::string>();
        r.last_error = j.value("last_error", std::string());  // records before it had none
        r.submitted = TimeFromJson(j.at("submitted"));
        r.started = TimeFromJson(j.at("started"));
        r.finished = TimeFromJson(j.at("finished"));
        r.tasks_total = Integer<int>(j.at("tasks_total"));
        r.tasks_done = Integer<int>(j.at("tasks_done"));
        r.tasks_running = Integer<int>(j.at("tasks_running"));
        r.retries = Integer<int>(j.at("retries"));
        r.tasks_leased = IntegerOr(j, "tasks_leased", 0);
        r.stats.samples = Integer<uint64_t>(j.at("samples"));
        r.stats.rays = Integer<uint64_t>(j.at("rays"));
        r.stats.invalid_samples = Integer<uint64_t>(j.at("invalid_samples"));
        r.result_path = j.at("result_path").get<std::string>();
        return r;
    } catch (const std::exception& e) {
        return absl::DataLossError(absl::StrCat("the stored record is unreadable: ", e.what()));
    }
}

}  // namespace lf
