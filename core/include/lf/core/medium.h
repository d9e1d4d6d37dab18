// Participating media as a scene describes them: homogeneous ones and grids read from OpenVDB
// files (lf/core/volume_grid.h loads them). Radiance through a medium follows the volume
// rendering equation dL/ds = -sigma_t L + sigma_a Le + sigma_s Int p L_i dw. The kernels turn
// this model into their own sampling structures (lf/kernels/media.h).
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "lf/core/affine.h"
#include "lf/core/rgb.h"
#include "lf/core/vec.h"

namespace lf {

// A float grid on OpenVDB's index lattice: value (x, y, z) sits at index-space point (x, y, z)
// (voxel centres are integer points), and a point between lattice points reads the trilinear
// blend of its 8 neighbours, as OpenVDB's BoxSampler. Only the active bounding box is stored,
// densely; outside it every value is `background`.
struct VolumeGrid {
    std::string name;                // "smoke.vdb#density", for messages
    std::array<int, 3> min{0, 0, 0};  // index of values[0]
    std::array<int, 3> size{0, 0, 0};  // lattice points along x, y, z
    std::vector<float> values;       // x fastest: values[(z * size[1] + y) * size[0] + x]
    float background = 0;
    // Index space to scene space: the file's own transform followed by the medium's `transform`.
    Affine index_to_world;
    // Its inverse: scene space to index space.
    Affine world_to_index;

    // The lattice value at (x, y, z) (index coordinates), `background` outside the box.
    float At(int x, int y, int z) const {
        x -= min[0], y -= min[1], z -= min[2];
        if (x < 0 || y < 0 || z < 0 || x >= size[0] || y >= size[1] || z >= size[2]) {
            return background;
        }
        return values[(size_t(z) * size_t(size[1]) + size_t(y)) * size_t(size[0]) + size_t(x)];
    }
    // Trilinear at an index-space point.
    float Lookup(const Vec3d& q) const;
};

// One medium of Scene::media. Coefficients are per metre (scene unit) with `scale` already
// applied.
struct Medium {
    enum class Type { kHomogeneous, kGrid };

    std::string name;  // the key in the JSON "media" object, for messages
    Type type = Type::kHomogeneous;
    // Absorption and scattering coefficients; a grid's at density 1 (the density grid
    // multiplies both).
    Rgb sigma_a{0.0f}, sigma_s{0.0f};
    // Henyey-Greenstein asymmetry: the mean cosine of the scattering angle, in (-1, 1).
    float g = 0;
    // Le: emitted radiance (W m^-2 sr^-1); the source term is sigma_a Le (radiance per metre),
    // so a medium that does not absorb does not emit, and an optically thick one shows Le.
    Rgb emission{0.0f};

    // kGrid only. `density` multiplies sigma_a and sigma_s; `emission_grid` multiplies
    // `emission`; `temperature` (kelvin = value * temperature_scale) adds Planck's black-body
    // radiance at that temperature to Le (absolute: luminance 683 lm/W times Int V B_lambda).
    std::shared_ptr<const VolumeGrid> density, emission_grid, temperature;
    double temperature_scale = 1;

    bool IsEmissive() const { return !emission.IsBlack() || temperature != nullptr; }
};

// A shape's media: the medium on the side its normal points away from (interior) and towards
// (exterior); -1 is vacuum. A shape without an interface (`has_interface` false) leaves a ray
// in the medium it was in (pbrt-v4's MediumInterface).
struct MediumInterface {
    bool has_interface = false;
    int interior = -1, exterior = -1;  // indices in Scene::media, -1 vacuum
};

}  // namespace lf
