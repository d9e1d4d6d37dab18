#include "lf/job/scene_files.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "absl/strings/str_split.h"
#include "lf/core/scene_loader.h"

namespace lf {

namespace fs = std::filesystem;

absl::Status CheckScenePath(const std::string& path) {
    bool ok = !path.empty() && path[0] != '/' && path.find('\\') == std::string::npos;
    for (absl::string_view part : absl::StrSplit(path, '/')) {
        ok = ok && !part.empty() && part != "." && part != "..";
    }
    if (ok) return absl::OkStatus();
    return absl::InvalidArgumentError(
        "scene file path '" + path +
        "' must be relative to the scene's folder and stay inside it (no '..', not absolute)");
}

absl::StatusOr<Scene> LoadSceneFromBlobs(
    const BlobRef& scene, const std::vector<BlobRef>& files,
    const std::function<std::string(const std::string& hash)>& blob_file,
    const std::string& scratch_dir) {
    if (absl::Status s = CheckScenePath(scene.path); !s.ok()) return s;
    std::error_code ec;
    fs::create_directories(scratch_dir, ec);
    if (ec) return absl::InternalError(scratch_dir + ": " + ec.message());
    struct Cleanup {
        std::string dir;
        ~Cleanup() {
            std::error_code ignored;
            fs::remove_all(dir, ignored);
        }
    } cleanup{scratch_dir};

    for (const BlobRef& file : files) {
        if (absl::Status s = CheckScenePath(file.path); !s.ok()) return s;
        const fs::path target = fs::path(scratch_dir) / file.path;
        fs::create_directories(target.parent_path(), ec);
        // A hard link costs nothing; a copy works across file systems.
        fs::create_hard_link(blob_file(file.hash), target, ec);
        if (ec) fs::copy_file(blob_file(file.hash), target, ec);
        if (ec) return absl::InternalError(file.path + ": " + ec.message());
    }
    std::ifstream in(blob_file(scene.hash), std::ios::binary);
    if (!in) return absl::InternalError(scene.path + ": its blob cannot be read");
    std::stringstream json;
    json << in.rdbuf();
    return ParseScene(json.str(), scene.path, scratch_dir);
}

}  // namespace lf
