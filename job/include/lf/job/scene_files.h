// A scene on the farm is its JSON plus the files it names, each stored as a blob by content
// hash and referred to by the name the JSON uses. The server (to validate a submission) and
// workers (to render) load it through those references only: a scene reaches the files uploaded
// with it and nothing else of the machine it is loaded on.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/scene.h"
#include "lf/core/scene_loader.h"

namespace lf {

// A file of a scene and its blob. `path` is the name as the scene JSON writes it ("mesh.obj",
// "../shared/bunny.ply", "/home/me/x.obj"): a key the loader looks names up by, never a path
// opened on the server or a worker. The scene file's own `path` is its file name, for messages.
struct BlobRef {
    std::string path;
    std::string hash;  // SHA-256, lowercase hex
    uint64_t size = 0;
};

// The longest name a BlobRef may carry.
inline constexpr size_t kMaxScenePathBytes = 4096;

// InvalidArgument unless `path` is a usable key: not empty, at most kMaxScenePathBytes, and
// without control characters (it appears in messages and logs).
absl::Status CheckScenePath(const std::string& path);

// Parses the scene whose JSON is blob `scene`, reading the files it names from `files` by the
// exact name in the JSON (`blob_file` maps a hash to the local file holding that blob). A name
// not among `files` is an error naming the JSON field and the name only, whatever exists on this
// machine. InvalidArgument also for two files of one name with different contents; Cancelled
// once `cancel` is set, checked before each file. A scene blob whose name ends in .gltf or .glb
// is a glTF file (ParseScene); `options` are the job's --camera and --resolution.
absl::StatusOr<Scene> LoadSceneFromBlobs(
    const BlobRef& scene, const std::vector<BlobRef>& files,
    const std::function<std::string(const std::string& hash)>& blob_file,
    const std::atomic<bool>* cancel = nullptr, const SceneOptions& options = {});

}  // namespace lf
