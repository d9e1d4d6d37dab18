// A scene on the farm is its JSON plus the files it names, each stored as a blob by content
// hash. The server (to validate a submission) and workers (to render) load it by laying the
// blobs out under a scratch folder at the paths the JSON uses.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/scene.h"

namespace lf {

// A file of a scene and its blob. Paths of the files a scene names are relative to the scene
// file's folder; the scene file's own path is just its name.
struct BlobRef {
    std::string path;
    std::string hash;  // SHA-256, lowercase hex
    uint64_t size = 0;
};

// InvalidArgument unless `path` is relative, '/'-separated, without '.' or '..' parts: a path
// that cannot leave the scratch folder.
absl::Status CheckScenePath(const std::string& path);

// Parses the scene from blob files (`blob_file` maps a hash to its file) laid out under
// `scratch_dir`, which is created and removed again. Errors are the loader's, naming
// `scene.path`.
absl::StatusOr<Scene> LoadSceneFromBlobs(
    const BlobRef& scene, const std::vector<BlobRef>& files,
    const std::function<std::string(const std::string& hash)>& blob_file,
    const std::string& scratch_dir);

}  // namespace lf
