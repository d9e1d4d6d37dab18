// glTF 2.0 files (.gltf with its buffers and images, or .glb) into the scene model, through
// tinygltf. Every file the glTF names is read through a SceneFileReader, so a glTF loads the same
// way from the user's disk and from the blobs uploaded to the farm; images are decoded by
// lf::DecodeTexture, never by tinygltf. docs/scene-format.md ("glTF 2.0") says what is imported
// and how.
#pragma once

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "lf/core/affine.h"
#include "lf/core/scene.h"
#include "lf/core/scene_animation.h"
#include "lf/core/scene_loader.h"

namespace lf {

// A camera of a glTF file, placed by its node.
struct GltfCamera {
    std::string name;  // the node's name, or the camera's when the node has none
    CameraSpec spec;
    // Why the camera cannot render ("cameras[1]: yfov 0 ..."): an error only when
    // it is chosen, so a file is never refused for a camera it does not render from.
    std::string error;
    // Its node in GltfImport::animation, when the import collects one; -1 otherwise.
    int node = -1;
};

// The image side a glTF camera gets for its longer side (the other from its aspectRatio; square
// without one) unless the user gives --resolution.
inline constexpr int kGltfLongerSide = 1024;

struct GltfImport {
    // The folder the glTF's relative URIs are resolved against, as the reader takes names: ""
    // for a glTF that is itself the scene file (the reader resolves beside it), "models" for
    // "models/car.gltf" included from a JSON scene.
    std::string base_dir;
    // Applied after the file's own node transforms: a JSON scene's "transform" of the included
    // file.
    Affine transform;
    // Where the file's animations, skins and morph targets go (lf/core/scene_animation.h),
    // with the node tree and what each node drives, when the file has any of them; null:
    // ignored, the rest pose only.
    SceneAnimation* animation = nullptr;
    // Required with `animation`: where a fault in that data goes (InvalidArgument naming the
    // file and the glTF object: "car.gltf: animations[0].channels[2]: ..."). Such a file still
    // loads in its rest pose, with a warning, and what went into `animation` is incomplete.
    absl::Status* animation_error = nullptr;
};

// Appends the default scene of glTF file `name` (its bytes `bytes`, JSON or binary) to `scene`:
// materials (and the default material, if a primitive has none), one TriangleMesh per triangle
// primitive, point, spot and directional lights and the images the materials use. The file's
// cameras, in node order, go to `cameras`; lossy imports are described in `warnings`.
// `read_file` gets the names the glTF uses, resolved against options.base_dir; `name` names
// the glTF in image names. InvalidArgument (or the reader's error) naming the glTF object, e.g.
// "meshes[0] \"Cube\".primitives[1]: mode 1 (LINES) is not supported; only triangles"; the
// caller adds which file.
absl::Status AppendGltf(const std::string& bytes, const std::string& name,
                        const SceneFileReader& read_file, const GltfImport& options, Scene& scene,
                        std::vector<GltfCamera>& cameras, std::vector<std::string>& warnings);

// The camera named `name` among `cameras` (empty name: the first). NotFound listing the names
// when there is no such camera, or when there is none at all; InvalidArgument with its error for
// a camera that cannot render.
absl::StatusOr<const GltfCamera*> ChooseGltfCamera(const std::vector<GltfCamera>& cameras,
                                                   const std::string& name);

// True for names ending in .gltf or .glb, in any case.
bool IsGltfName(const std::string& name);

}  // namespace lf
