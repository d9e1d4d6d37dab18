#include "lf/core/gltf_scene.h"

#include <tiny_gltf.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "gltf_importer.h"
#include "lf/core/texture_io.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

// What tinygltf's callbacks need: our reader, the glTF's folder, and where to put what they
// found. tinygltf calls them with the name it would open, joined to the base directory we give
// it (none): the URI as the glTF writes it, decoded.
struct LoadContext {
    const SceneFileReader* read_file;
    std::string base;  // the glTF's folder as the scene names it, "" beside the scene
    std::string name;  // the glTF, for image names
    std::map<std::string, absl::Status> read_errors;  // by URI
    std::map<int, absl::StatusOr<std::shared_ptr<const TextureImage>>> images;
};

bool AlwaysExists(const std::string&, void*) { return true; }
std::string AsIs(const std::string& path, void*) { return path; }

bool ReadThroughReader(std::vector<unsigned char>* out, std::string* err, const std::string& uri,
                       void* user) {
    auto* context = static_cast<LoadContext*>(user);
    const fs::path path(uri);
    const std::string name =
        path.is_absolute() ? uri : (fs::path(context->base) / path).lexically_normal().string();
    absl::StatusOr<std::string> bytes = (*context->read_file)(name);
    if (!bytes.ok()) {
        context->read_errors[uri] = bytes.status();
        *err = std::string(bytes.status().message());
        return false;
    }
    out->assign(bytes->begin(), bytes->end());
    return true;
}

bool NeverWrite(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
    *err = "writing is not supported";
    return false;
}

bool DecodeImage(tinygltf::Image* image, const int index, std::string*, std::string*, int, int,
                 const unsigned char* bytes, int size, void* user) {
    auto* context = static_cast<LoadContext*>(user);
    const std::string name = image->uri.empty() || image->uri.starts_with("data:")
                                 ? absl::StrCat(context->name, "#image", index)
                                 : image->uri;
    context->images.emplace(
        index,
        DecodeTexture(std::string(reinterpret_cast<const char*>(bytes), size_t(size)), name));
    return true;
}

}  // namespace

bool IsGltfName(const std::string& name) {
    const std::string ext = absl::AsciiStrToLower(fs::path(name).extension().string());
    return ext == ".gltf" || ext == ".glb";
}

absl::Status AppendGltf(const std::string& bytes, const std::string& name,
                        const SceneFileReader& read_file, const GltfImport& options, Scene& scene,
                        std::vector<GltfCamera>& cameras, std::vector<std::string>& warnings) {
    LoadContext context{&read_file, options.base_dir, name, {}, {}};
    tinygltf::TinyGLTF loader;
    loader.SetFsCallbacks({&AlwaysExists, &AsIs, &ReadThroughReader, &NeverWrite, &context});
    loader.SetImageLoader(&DecodeImage, &context);
    tinygltf::Model model;
    std::string err, warn;
    const bool binary = bytes.size() >= 4 && bytes.compare(0, 4, "glTF") == 0;
    if (bytes.size() > std::numeric_limits<unsigned int>::max()) {
        return absl::InvalidArgumentError("larger than 4 GB");
    }
    if (binary) {
        // tinygltf says only "Invalid glTF binary" for the commonest .glb fault: a cut-off copy.
        uint32_t declared = 0;
        if (bytes.size() >= 12) std::memcpy(&declared, bytes.data() + 8, 4);
        if (bytes.size() < 12 || declared > bytes.size()) {
            return absl::InvalidArgumentError(absl::StrCat(
                "truncated glTF binary (.glb): ", bytes.size(), " bytes, its header ",
                bytes.size() < 12 ? "alone needs 12" : absl::StrCat("declares ", declared)));
        }
    }
    const std::string prepared = gltf_internal::PrepareDraco(bytes, binary);
    const bool ok =
        binary ? loader.LoadBinaryFromMemory(
                     &model, &err, &warn, reinterpret_cast<const unsigned char*>(prepared.data()),
                     unsigned(prepared.size()), "")
               : loader.LoadASCIIFromString(&model, &err, &warn, prepared.data(),
                                            unsigned(prepared.size()), "");
    if (!ok) {
        // A file the reader could not give is the cause the user can act on.
        for (const auto& [uri, status] : context.read_errors) {
            // Images that cannot be read only warn in tinygltf: this is a buffer.
            return absl::Status(status.code(),
                                absl::StrCat("buffer uri \"", uri, "\": ", status.message()));
        }
        absl::StripTrailingAsciiWhitespace(&err);
        return absl::InvalidArgumentError(
            absl::StrCat("not a valid glTF ", binary ? "binary (.glb)" : "file", ": ", err));
    }
    try {
        gltf_internal::GltfImporter(model, name, options, scene, cameras, warnings, context.images,
                                    context.read_errors)
            .Import();
    } catch (const gltf_internal::GltfError& e) {
        return absl::InvalidArgumentError(e.message);
    }
    return absl::OkStatus();
}

absl::StatusOr<CameraSpec> ChooseGltfCamera(const std::vector<GltfCamera>& cameras,
                                            const std::string& name) {
    if (cameras.empty()) {
        return absl::NotFoundError(
            "no camera; render with --camera auto (frames the whole scene), add one to the "
            "glTF, or include the file from a JSON scene that gives a camera");
    }
    const auto usable = [](const GltfCamera& camera) -> absl::StatusOr<CameraSpec> {
        if (!camera.error.empty()) return absl::InvalidArgumentError(camera.error);
        return camera.spec;
    };
    if (name.empty()) return usable(cameras.front());
    std::vector<std::string> names;
    for (const GltfCamera& camera : cameras) {
        if (camera.name == name) return usable(camera);
        names.push_back(absl::StrCat("\"", camera.name, "\""));
    }
    // Unnamed cameras (most sample assets) by their place in node order.
    if (size_t index = 0; absl::SimpleAtoi(name, &index) && index < cameras.size()) {
        return usable(cameras[index]);
    }
    return absl::NotFoundError(absl::StrCat("no camera named \"", name, "\"; the cameras are ",
                                            absl::StrJoin(names, ", "), " (or 0 to ",
                                            cameras.size() - 1, " by their order)"));
}

}  // namespace lf
