#include "lf/kernels/radiosity_display.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <tuple>

#include "absl/strings/str_cat.h"
#include "lf/core/image_io.h"
#include "lf/core/photometry.h"
#include "lf/kernels/lights.h"
#include "lf/kernels/radiosity_surfaces.h"

namespace lf {

namespace {

constexpr float kInvPi = float(1 / std::numbers::pi);

// Sides meeting at a vertex at more than this angle are a crease, not one smooth surface.
const double kCreaseCosine = std::cos(30 * std::numbers::pi / 180);

}  // namespace

absl::StatusOr<RadiosityShading> ParseRadiosityShading(std::string_view name) {
    for (RadiosityShading s : {RadiosityShading::kFlat, RadiosityShading::kSmooth}) {
        if (name == RadiosityShadingName(s)) return s;
    }
    return absl::InvalidArgumentError(absl::StrCat("unknown radiosity display '", std::string(name),
                                                   "' (expected flat or smooth)"));
}

const char* RadiosityShadingName(RadiosityShading shading) {
    return shading == RadiosityShading::kFlat ? "flat" : "smooth";
}

std::vector<std::array<Rgb, 3>> SmoothCorners(const PatchMesh& mesh,
                                              std::span<const Rgb> radiosity) {
    const auto& sides = mesh.sides();
    const auto& patches = mesh.patches();
    // Sides around each vertex, as offsets into one array.
    std::vector<int32_t> start(mesh.vertices().size() + 1, 0), around(sides.size() * 3);
    for (const PatchMesh::Side& s : sides) {
        for (uint32_t v : patches[size_t(s.patch)].vertices) ++start[v + 1];
    }
    for (size_t v = 0; v + 1 < start.size(); ++v) start[v + 1] += start[v];
    std::vector<int32_t> fill(start.begin(), start.end() - 1);
    for (int32_t s = 0; s < int32_t(sides.size()); ++s) {
        for (uint32_t v : patches[size_t(sides[size_t(s)].patch)].vertices) {
            around[size_t(fill[v]++)] = s;
        }
    }

    std::vector<std::array<Rgb, 3>> corners(sides.size());
    for (int32_t s = 0; s < int32_t(sides.size()); ++s) {
        const Vec3d n = mesh.SideNormal(s);
        const auto& vertices = patches[size_t(sides[size_t(s)].patch)].vertices;
        for (size_t c = 0; c < 3; ++c) {
            double sum[3] = {0, 0, 0}, area = 0;
            for (int32_t k = start[vertices[c]]; k < start[vertices[c] + 1]; ++k) {
                const int32_t other = around[size_t(k)];
                if (sides[size_t(other)].back != sides[size_t(s)].back ||
                    Dot(mesh.SideNormal(other), n) < kCreaseCosine) {
                    continue;
                }
                const double a = patches[size_t(sides[size_t(other)].patch)].area;
                area += a;
                for (int ch = 0; ch < 3; ++ch) sum[ch] += a * radiosity[size_t(other)][ch];
            }
            corners[size_t(s)][c] =
                Rgb(float(sum[0] / area), float(sum[1] / area), float(sum[2] / area));
        }
    }
    return corners;
}

RadiosityDisplay::RadiosityDisplay(const EmbreeScene& scene, const PatchMesh& mesh,
                                   std::vector<Rgb> radiosity, std::vector<Rgb> irradiance,
                                   RadiosityShading shading)
    : scene_(scene),
      mesh_(mesh),
      surfaces_(std::make_unique<RadiositySurfaces>(scene)),
      radiosity_(std::move(radiosity)),
      irradiance_(std::move(irradiance)) {
    const Scene& s = scene.scene();
    if (s.environment ||
        std::any_of(s.directional_lights.begin(), s.directional_lights.end(),
                    [](const DirectionalLight& l) { return l.angular_diameter > 0; })) {
        sky_ = std::make_unique<LightSampler>(scene, LightStrategy::kPower);
    }
    if (shading == RadiosityShading::kSmooth) {
        corners_ = SmoothCorners(mesh_, radiosity_);
        irradiance_corners_ = SmoothCorners(mesh_, irradiance_);
    }
}

RadiosityDisplay::~RadiosityDisplay() = default;

Rgb RadiosityDisplay::Li(const Ray& ray, Sampler&, RenderStats& stats) const {
    ++stats.rays;
    const std::optional<SurfaceHit> hit = scene_.Intersect(ray);
    // The sky and sun disks, as the path tracer shows them.
    if (!hit) return sky_ ? sky_->EscapedRadiance(ray.d) : Rgb(0);
    if (hit->mesh < 0) return Rgb(0);
    return Radiance(hit->mesh, hit->primitive, hit->b1, hit->b2, Dot(ray.d, hit->n) > 0);
}

Rgb RadiosityDisplay::Shade(std::span<const Rgb> per_side,
                            const std::vector<std::array<Rgb, 3>>& corners, int mesh, int primitive,
                            double b1, double b2, bool back) const {
    const PatchPoint point = mesh_.Locate(mesh, primitive, b1, b2);
    const int32_t side = mesh_.patches()[size_t(point.patch)].sides[back ? 1 : 0];
    if (side < 0) return Rgb(0);
    if (corners.empty()) return per_side[size_t(side)];
    const auto& c = corners[size_t(side)];
    return c[0] * float(point.w[0]) + c[1] * float(point.w[1]) + c[2] * float(point.w[2]);
}

Rgb RadiosityDisplay::Radiance(int mesh, int primitive, double b1, double b2, bool back) const {
    if (!surfaces_->Varies(mesh)) {
        return Shade(radiosity_, corners_, mesh, primitive, b1, b2, back) * kInvPi;
    }
    // Textured: the albedo and emission at the point, under the patch's irradiance.
    const PatchPoint point = mesh_.Locate(mesh, primitive, b1, b2);
    if (mesh_.patches()[size_t(point.patch)].sides[back ? 1 : 0] < 0) return Rgb(0);
    const RadiositySurfaces::Point at = surfaces_->At(mesh, primitive, float(b1), float(b2));
    const Material& m =
        scene_.scene().materials[size_t(scene_.scene().meshes[size_t(mesh)].material)];
    const Rgb emitted = !back || m.two_sided_emission ? at.emission : Rgb();
    return at.reflectance * Irradiance(mesh, primitive, b1, b2, back) * kInvPi + emitted;
}

Rgb RadiosityDisplay::Irradiance(int mesh, int primitive, double b1, double b2, bool back) const {
    return Shade(irradiance_, irradiance_corners_, mesh, primitive, b1, b2, back);
}

namespace {

// The lux at corner c of side s as `display` shades it, a hair inside the patch so that the point
// is the patch's own; printed to 4 significant digits, the PLY's text and a vertex's key.
std::string CornerLux(const PatchMesh& mesh, const RadiosityDisplay& display, size_t s, size_t c) {
    const PatchMesh::Side& side = mesh.sides()[s];
    const PatchMesh::Patch& patch = mesh.patches()[size_t(side.patch)];
    std::array<double, 3> w;
    w.fill(1e-6);
    w[c] = 1 - 2e-6;
    const auto [b1, b2] = mesh.TriangleBarycentrics(side.patch, w);
    char text[32];
    std::snprintf(text, sizeof text, "%.4g",
                  Photometric(display.Irradiance(patch.mesh, patch.primitive, b1, b2, side.back)));
    return text;
}

}  // namespace

absl::Status WriteRadiosityPly(const std::string& path, const PatchMesh& mesh,
                               std::span<const Rgb> radiosity, const RadiosityDisplay& display) {
    const std::vector<std::array<Rgb, 3>> corners = SmoothCorners(mesh, radiosity);
    using Colour = std::array<uint8_t, 3>;
    struct Vertex {
        uint32_t position;
        Colour colour;
        std::string lux;
    };
    std::map<std::tuple<uint32_t, bool, Colour, std::string>, uint32_t> index;
    std::vector<Vertex> vertices;
    std::vector<std::array<uint32_t, 3>> faces;
    for (size_t s = 0; s < mesh.sides().size(); ++s) {
        const PatchMesh::Side& side = mesh.sides()[s];
        const auto& patch_vertices = mesh.patches()[size_t(side.patch)].vertices;
        std::array<uint32_t, 3> face;
        for (size_t c = 0; c < 3; ++c) {
            const Rgb radiance = corners[s][c] * kInvPi;
            const Colour colour{EncodeSrgb8(radiance.r), EncodeSrgb8(radiance.g),
                                EncodeSrgb8(radiance.b)};
            std::string lux = CornerLux(mesh, display, s, c);
            const auto key = std::tuple(patch_vertices[c], side.back, colour, lux);
            const auto [it, inserted] = index.try_emplace(key, uint32_t(vertices.size()));
            if (inserted) vertices.push_back({patch_vertices[c], colour, std::move(lux)});
            face[c] = it->second;
        }
        if (side.back) std::swap(face[1], face[2]);
        faces.push_back(face);
    }

    FILE* file = std::fopen(path.c_str(), "w");
    if (!file) return absl::NotFoundError(absl::StrCat(path, ": cannot write PLY"));
    std::fprintf(file,
                 "ply\nformat ascii 1.0\ncomment lightfarm radiosity: vertex colours are B/pi, "
                 "sRGB\ncomment illuminance: lux arriving on the side, as the display shades "
                 "it\nelement vertex %zu\nproperty float x\nproperty float y\nproperty float "
                 "z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nproperty "
                 "float illuminance\nelement face %zu\nproperty list uchar int "
                 "vertex_indices\nend_header\n",
                 vertices.size(), faces.size());
    for (const Vertex& v : vertices) {
        const Vec3d& p = mesh.vertices()[v.position];
        std::fprintf(file, "%.9g %.9g %.9g %d %d %d %s\n", p.x, p.y, p.z, v.colour[0], v.colour[1],
                     v.colour[2], v.lux.c_str());
    }
    for (const auto& f : faces) std::fprintf(file, "3 %u %u %u\n", f[0], f[1], f[2]);
    const bool failed = std::ferror(file) != 0;
    if (std::fclose(file) != 0 || failed) {
        return absl::DataLossError(absl::StrCat(path, ": error writing PLY"));
    }
    return absl::OkStatus();
}

}  // namespace lf
