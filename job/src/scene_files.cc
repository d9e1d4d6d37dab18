#include "lf/job/scene_files.h"

#include <map>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "lf/core/file_util.h"
#include "lf/core/scene_loader.h"

namespace lf {

absl::Status CheckScenePath(const std::string& path) {
    if (path.empty() || path.size() > kMaxScenePathBytes) {
        return absl::InvalidArgumentError(absl::StrCat(
            "scene file name of ", path.size(), " bytes: expected 1 to ", kMaxScenePathBytes));
    }
    for (unsigned char c : path) {
        if (c < 0x20 || c == 0x7f) {
            return absl::InvalidArgumentError(
                absl::StrCat("scene file name with control character ", int(c), ": \"",
                             absl::CHexEscape(path), "\""));
        }
    }
    return absl::OkStatus();
}

absl::StatusOr<Scene> LoadSceneFromBlobs(
    const BlobRef& scene, const std::vector<BlobRef>& files,
    const std::function<std::string(const std::string& hash)>& blob_file,
    const std::atomic<bool>* cancel, const SceneOptions& options) {
    if (absl::Status s = CheckScenePath(scene.path); !s.ok()) return s;
    std::map<std::string, std::string> hash_of;  // by name
    for (const BlobRef& file : files) {
        if (absl::Status s = CheckScenePath(file.path); !s.ok()) return s;
        const auto [it, inserted] = hash_of.emplace(file.path, file.hash);
        if (!inserted && it->second != file.hash) {
            return absl::InvalidArgumentError(absl::StrCat(
                scene.path, ": \"", file.path, "\" uploaded twice with different contents"));
        }
    }
    // The blob files are this machine's; a message says which upload failed, not where it is.
    auto read_blob = [&](const std::string& name,
                         const std::string& hash) -> absl::StatusOr<std::string> {
        if (cancel && cancel->load()) return absl::CancelledError("loading cancelled");
        absl::StatusOr<std::string> bytes = ReadFile(blob_file(hash));
        if (!bytes.ok()) {
            return absl::InternalError(absl::StrCat("the uploaded ", name, " (blob ", hash,
                                                    ") cannot be read on this machine"));
        }
        return bytes;
    };
    const SceneFileReader read_uploaded =
        [&](const std::string& name) -> absl::StatusOr<std::string> {
        const auto it = hash_of.find(name);
        if (it == hash_of.end()) {
            return absl::NotFoundError("not among the files uploaded with the scene");
        }
        return read_blob(name, it->second);
    };
    absl::StatusOr<std::string> json = read_blob(scene.path, scene.hash);
    if (!json.ok()) return json.status();
    return ParseScene(*json, scene.path, read_uploaded, options);
}

}  // namespace lf
