#include "lf/core/mesh_tangents.h"

namespace lf {

void ComputeTangents(TriangleMesh& mesh, int tex_coord) {
    const std::vector<Vec2>& uvs = mesh.Uvs(tex_coord);
    const size_t n = mesh.positions.size();
    std::vector<Vec3d> tangent(n), bitangent(n), normal(n);
    for (const auto& t : mesh.triangles) {
        const Vec3d e1 = mesh.positions[t[1]] - mesh.positions[t[0]];
        const Vec3d e2 = mesh.positions[t[2]] - mesh.positions[t[0]];
        const Vec2 &uv0 = uvs[t[0]], &uv1 = uvs[t[1]], &uv2 = uvs[t[2]];
        const double du1 = uv1.x - uv0.x, dv1 = uv1.y - uv0.y;
        const double du2 = uv2.x - uv0.x, dv2 = uv2.y - uv0.y;
        const double r = du1 * dv2 - du2 * dv1;
        const Vec3d face = Cross(e1, e2);
        for (uint32_t v : t) normal[v] += face;
        if (r == 0) continue;  // no uv area: says nothing of the directions
        const Vec3d du = (e1 * dv2 - e2 * dv1) / r, dv = (e2 * du1 - e1 * du2) / r;
        for (uint32_t v : t) {
            tangent[v] += du;
            bitangent[v] -= dv;
        }
    }
    mesh.tangents.resize(n);
    for (size_t i = 0; i < n; ++i) {
        const Vec3d nv = mesh.normals.empty() ? normal[i] : Vec3d(mesh.normals[i]);
        const Vec3d unit_n = LengthSquared(nv) > 0 ? Normalize(nv) : Vec3d(0, 0, 1);
        Vec3d t = tangent[i] - unit_n * Dot(unit_n, tangent[i]);
        // Any direction in the surface where the uvs give none.
        t = LengthSquared(t) > 0 ? Normalize(t) : Vec3d(Frame::FromNormal(Vec3(unit_n)).s);
        const float w = Dot(Cross(unit_n, t), bitangent[i]) < 0 ? -1.0f : 1.0f;
        mesh.tangents[i] = {float(t.x), float(t.y), float(t.z), w};
    }
}

void ComputeMissingTangents(Scene& scene) {
    for (TriangleMesh& mesh : scene.meshes) {
        const TextureRef& map = scene.materials[size_t(mesh.material)].normal_texture;
        if (!map.valid() || !mesh.tangents.empty()) continue;
        if (!mesh.Uvs(map.tex_coord).empty()) ComputeTangents(mesh, map.tex_coord);
    }
}

}  // namespace lf
