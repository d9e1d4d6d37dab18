// The Cornell box stored in a farm's blob store, as a submission names its scene: for tests that
// drive lf::Farm directly, without a client uploading it.
#pragma once

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "lf/job/digest.h"
#include "lf/server/farm.h"

namespace lf::testing {

inline absl::StatusOr<BlobRef> StoreCornellBox(Farm& farm, int resolution) {
    std::ifstream in(std::filesystem::path(LF_TEST_SCENES) / "cornell_box.json");
    std::stringstream text;
    text << in.rdbuf();
    nlohmann::json scene = nlohmann::json::parse(text.str());
    scene["camera"]["resolution"] = {resolution, resolution};
    const std::string json = scene.dump();
    const BlobRef ref{"scene.json", Sha256Hex(json), json.size()};
    absl::StatusOr<std::unique_ptr<BlobStore::Upload>> upload =
        farm.StartUpload(ref.hash, ref.size);
    if (!upload.ok()) return upload.status();
    if (absl::Status s = (*upload)->Append(json); !s.ok()) return s;
    if (absl::Status s = (*upload)->Finish(); !s.ok()) return s;
    return ref;
}

}  // namespace lf::testing
