#include <tiny_obj_loader.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <istream>
#include <map>
#include <optional>
#include <sstream>
#include <streambuf>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "mesh_parse.h"

namespace lf::mesh_internal {
namespace {

// Calls visit(line, fields) for each non-blank line at or after `from` (lines count from 1,
// ending as tinyobjloader counts them: \n, \r\n or a lone \r) until it returns false.
template <typename Visit>
void ForEachLine(std::string_view text, Visit visit, size_t from = 1) {
    size_t line = 0, pos = 0;
    while (pos < text.size()) {
        const size_t end = std::min(text.find_first_of("\r\n", pos), text.size());
        ++line;
        if (line >= from) {
            const std::vector<std::string> fields = SplitFields(text.substr(pos, end - pos));
            if (!fields.empty() && !visit(line, fields)) return;
        }
        pos = end + (text.substr(end, 2) == "\r\n" ? 2 : 1);
    }
}

// tinyobjloader does not say which line a record came from. On an error this finds the line
// number (from 1) of the first line at or after `from` whose fields `match`; 0 if none does.
template <typename Match>
size_t FindLine(std::string_view text, Match match, size_t from = 1) {
    size_t found = 0;
    ForEachLine(
        text,
        [&](size_t line, const std::vector<std::string>& fields) {
            if (match(fields)) found = line;
            return found == 0;
        },
        from);
    return found;
}

// The line of the `n`-th (from 0) record `keyword` with at least `min_fields` fields after it.
size_t FindRecordLine(std::string_view text, std::string_view keyword, size_t n,
                      size_t min_fields = 0) {
    size_t seen = 0;
    return FindLine(text, [&](const std::vector<std::string>& f) {
        return f[0] == keyword && f.size() > min_fields && seen++ == n;
    });
}

bool EqualsIgnoringCase(std::string_view a, std::string_view b) {
    return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](char x, char y) {
        return std::tolower(static_cast<unsigned char>(x)) ==
               std::tolower(static_cast<unsigned char>(y));
    });
}

// `name` as the scene's file reader knows it: relative names are relative to the folder of the
// file that names them, as OBJ and MTL files mean them.
std::string Beside(const std::string& file, const std::string& name) {
    const std::filesystem::path path(name);
    if (path.is_absolute()) return path.lexically_normal().string();
    return (std::filesystem::path(file).parent_path() / path).lexically_normal().string();
}

// An MTL file as read, for messages that name its lines: each material's block (from its
// `newmtl` line to the next) with the line of the first use of each keyword (lowercase) in it,
// found in one pass, so naming the lines of thousands of materials costs no search each.
struct MtlText {
    struct Block {
        size_t start = 0;  // the `newmtl` line
        std::map<std::string, size_t> lines;
    };

    MtlText(std::string name_, std::string text_) : name(std::move(name_)), text(std::move(text_)) {
        Block* block = nullptr;
        ForEachLine(text, [&](size_t line, const std::vector<std::string>& f) {
            if (f[0] == "newmtl") {
                // tinyobjloader names a material by the rest of its `newmtl` line.
                const auto [it, inserted] =
                    blocks.try_emplace(absl::StrJoin(f.begin() + 1, f.end(), " "), Block{line, {}});
                block = inserted ? &it->second : nullptr;  // the first definition's lines
            } else if (block) {
                block->lines.try_emplace(absl::AsciiStrToLower(f[0]), line);
            }
            return true;
        });
    }

    std::string name;  // as the reader knows it
    std::string text;
    std::map<std::string, Block> blocks;  // by material name
};

// Reads `mtllib` files through the scene's file reader (tinyobjloader would open them from
// the working directory), and remembers which file each material came from.
class MtlReader : public tinyobj::MaterialReader {
  public:
    MtlReader(const SceneFileReader& read_file, std::string obj_name)
        : read_file_(read_file), obj_name_(std::move(obj_name)) {}

    bool operator()(const std::string& name, std::vector<tinyobj::material_t>* materials,
                    std::map<std::string, int>* index, std::string* warn,
                    std::string* err) override {
        const std::string path = Beside(obj_name_, name);
        absl::StatusOr<std::string> text = read_file_(path);
        if (!text.ok()) {
            if (failure_.empty()) {
                failed_name_ = name;
                failure_ = absl::StrCat("mtllib \"", path, "\": ", text.status().message());
            }
            return false;
        }
        std::istringstream stream(*text);
        tinyobj::LoadMtl(index, materials, &stream, warn, err);
        file_of_.resize(materials->size(), files_.size());
        files_.emplace_back(path, *std::move(text));
        return true;
    }

    // The first MTL file that could not be read, and why; empty when all were.
    const std::string& failed_name() const { return failed_name_; }
    const std::string& failure() const { return failure_; }
    const MtlText& FileOf(size_t material) const { return files_[file_of_[material]]; }

  private:
    const SceneFileReader& read_file_;
    std::string obj_name_;
    std::vector<MtlText> files_;
    std::vector<size_t> file_of_;  // by material index
    std::string failed_name_, failure_;
};

// Turns the MTL materials the faces use into lf::Materials (docs/scene-format.md, "OBJ
// materials (MTL)"), collecting the image files they name.
class MtlConverter {
  public:
    MtlConverter(const MtlReader& reader, MeshFile& out) : reader_(reader), out_(out) {}

    Material Convert(const tinyobj::material_t& mtl, size_t index) {
        const MtlText& file = reader_.FileOf(index);
        // Each value's line, for messages: the key's first line in the material's block.
        const auto found = file.blocks.find(std::string(absl::StripAsciiWhitespace(mtl.name)));
        const MtlText::Block* block = found == file.blocks.end() ? nullptr : &found->second;
        const size_t start = block ? block->start : 0;
        // The line of `key` in this material's block, or 0.
        auto line_of = [&](const char* key) -> size_t {
            if (!block) return 0;
            const auto it = block->lines.find(absl::AsciiStrToLower(key));
            return it == block->lines.end() ? 0 : it->second;
        };
        auto where = [&](const char* key) {
            const size_t line = line_of(key);
            return absl::StrCat(file.name, ":", line > 0 ? line : start);
        };
        auto color = [&](const tinyobj::real_t* c, const char* key, float max) {
            const Rgb rgb(c[0], c[1], c[2]);
            for (int i = 0; i < 3; ++i) {
                if (!(rgb[i] >= 0 && std::isfinite(rgb[i]))) {
                    Fail("", absl::StrCat(where(key), ": material \"", mtl.name, "\": ", key,
                                          " must be finite and ≥ 0"));
                }
            }
            if (rgb.MaxComponent() <= max) return rgb;
            out_.warnings.push_back(absl::StrCat(where(key), ": material \"", mtl.name, "\": ", key,
                                                 " above ", max, " clamped to ", max));
            return Rgb(std::min(rgb.r, max), std::min(rgb.g, max), std::min(rgb.b, max));
        };
        auto texture = [&](const std::string& name, const tinyobj::texture_option_t& option,
                           const char* key, bool srgb) {
            return Texture(Beside(file.name, name), option, absl::StrCat(where(key), ": ", key),
                           srgb);
        };

        Material m;
        m.name = absl::StrCat(file.name, "#", mtl.name);
        // Without Kd, Blender's default 0.8, or the texture alone (tinyobjloader would say 0).
        m.reflectance = start == 0 || line_of("Kd") > 0 ? color(mtl.diffuse, "Kd", 1)
                        : mtl.diffuse_texname.empty()   ? Rgb(0.8f)
                                                        : Rgb(1);
        // The scene loader's bound on emitted radiance, 500 times the sun's. A map_Ke without Ke
        // emits the texture itself, as a JSON emission_texture alone does.
        m.emission = line_of("Ke") > 0 || mtl.emissive_texname.empty()
                         ? color(mtl.emission, "Ke", 1e10f)
                         : Rgb(1);
        if (!mtl.diffuse_texname.empty()) {
            m.base_color_texture = texture(mtl.diffuse_texname, mtl.diffuse_texopt, "map_Kd", true);
        }
        if (!mtl.emissive_texname.empty()) {
            m.emission_texture = texture(mtl.emissive_texname, mtl.emissive_texopt, "map_Ke", true);
        }
        // `norm` is a tangent-space normal map; so is what Blender writes as map_Bump.
        const bool norm = !mtl.normal_texname.empty();
        const std::string& normal_map = norm ? mtl.normal_texname : mtl.bump_texname;
        if (!normal_map.empty()) {
            const tinyobj::texture_option_t& option = norm ? mtl.normal_texopt : mtl.bump_texopt;
            m.normal_texture = texture(normal_map, option, norm ? "norm" : "map_Bump", false);
            m.normal_scale = option.bump_multiplier;
        }

        // Blinn-Phong specular (illum 2 and up) as the principled material's dielectric layer,
        // the way Blender's OBJ importer maps it: Ks's mean is Blender's Specular, whose 0.5
        // (what its exporter writes by default) is the plain dielectric, specular weight 1; Ns
        // is the perceptual roughness 1 - sqrt(Ns / 1000).
        const float ks = (mtl.specular[0] + mtl.specular[1] + mtl.specular[2]) / 3;
        const bool specular = mtl.illum >= 2 && ks > 0;
        m.specular = specular ? std::min(2 * ks, 1.0f) : 0;
        m.roughness = mtl.roughness > 0
                          ? std::min(float(mtl.roughness), 1.0f)
                          : 1 - std::sqrt(std::clamp(float(mtl.shininess), 0.0f, 1000.0f) / 1000);
        m.metallic = std::clamp(float(mtl.metallic), 0.0f, 1.0f);
        // Exporters write Ni 1 (or less) when they mean nothing: it would remove all reflection.
        if (mtl.ior > 1 && std::isfinite(mtl.ior)) m.ior = mtl.ior;

        const float d =
            std::isfinite(mtl.dissolve) ? std::clamp(float(mtl.dissolve), 0.0f, 1.0f) : 1.0f;
        const bool refracts = mtl.illum == 4 || mtl.illum == 6 || mtl.illum == 7 || mtl.illum == 9;
        if (d < 1 && refracts) {
            m.transmission = 1 - d;  // glass: the illumination models that refract
        } else if (d < 1 ||
                   (!mtl.alpha_texname.empty() && mtl.alpha_texname == mtl.diffuse_texname)) {
            // A cut-out: opacity d, times the base colour texture's alpha when map_d names it.
            m.opacity = d;
            m.alpha_mode = Material::AlphaMode::kMask;
        }
        if (!mtl.alpha_texname.empty() && mtl.alpha_texname != mtl.diffuse_texname) {
            Unsupported(mtl, where("map_d"), "map_d naming another file than map_Kd",
                        "the cut-out");
        }
        for (const auto& [name, key] : {std::pair{&mtl.specular_texname, "map_Ks"},
                                        {&mtl.specular_highlight_texname, "map_Ns"},
                                        {&mtl.roughness_texname, "map_Pr"},
                                        {&mtl.metallic_texname, "map_Pm"},
                                        {&mtl.displacement_texname, "disp"},
                                        {&mtl.reflection_texname, "refl"}}) {
            if (!name->empty()) Unsupported(mtl, where(key), key, "its variation");
        }

        if (specular || m.metallic > 0 || m.transmission > 0 || m.normal_texture.valid() ||
            m.emission_texture.valid()) {
            m.type = Material::Type::kPrincipled;
        }
        return m;
    }

  private:
    void Unsupported(const tinyobj::material_t& mtl, const std::string& where, const char* what,
                     const char* lost) {
        out_.warnings.push_back(absl::StrCat(where, ": material \"", mtl.name, "\": ", what,
                                             " is not supported; ", lost, " is lost"));
    }

    // A texture of the MTL file, its -s and -o options turned into a transform of the stored
    // (flipped) v: image v = 1 - (s (1 - v') + o) = s v' + (1 - s - o).
    TextureRef Texture(const std::string& name, const tinyobj::texture_option_t& option,
                       const std::string& where, bool srgb) {
        TextureRef ref;
        const auto found = std::find_if(out_.textures.begin(), out_.textures.end(),
                                        [&](const MeshFile::Texture& t) { return t.name == name; });
        ref.image = int(found - out_.textures.begin());
        if (found == out_.textures.end()) out_.textures.push_back({name, where});
        ref.srgb = option.colorspace.empty() ? srgb : EqualsIgnoringCase(option.colorspace, "srgb");
        if (option.clamp) ref.wrap_s = ref.wrap_t = TextureRef::Wrap::kClampToEdge;
        ref.scale = {float(option.scale[0]), float(option.scale[1])};
        ref.offset = {float(option.origin_offset[0]),
                      float(1 - option.scale[1] - option.origin_offset[1])};
        return ref;
    }

    const MtlReader& reader_;
    MeshFile& out_;
};

// Builds one mesh of the faces of one material.
struct ObjMeshBuilder {
    TriangleMesh mesh;
    bool normals = false, uvs = false;
    int material = -1;
    size_t first_face = 0;
};

// The mesh vertices made from a file's corners: each distinct (position, normal, texture
// coordinate) index triple of a mesh is one vertex. Chained per file position, since a position
// has only a few distinct corners (one per crease or seam): faster than hashing the triples.
class CornerVertices {
  public:
    explicit CornerVertices(size_t positions) : first_(positions, -1) {}

    // The vertex of (v, n, t) in mesh `builder`, or -1 if there is none yet.
    int64_t Find(int64_t v, int64_t n, int64_t t, uint32_t builder) const {
        for (int64_t k = first_[size_t(v)]; k >= 0; k = made_[size_t(k)].next) {
            const Made& m = made_[size_t(k)];
            if (m.n == n && m.t == t && m.builder == builder) return m.vertex;
        }
        return -1;
    }
    void Add(int64_t v, int64_t n, int64_t t, uint32_t builder, uint32_t vertex) {
        made_.push_back({n, t, first_[size_t(v)], builder, vertex});
        first_[size_t(v)] = int64_t(made_.size() - 1);
    }

  private:
    struct Made {
        int64_t n, t;
        int64_t next;  // the previous vertex made at the same position, or -1
        uint32_t builder, vertex;
    };
    std::vector<int64_t> first_;  // by file position: its last vertex made, or -1
    std::vector<Made> made_;
};

}  // namespace

MeshFile ParseObj(const std::string& text, const std::string& name,
                  const SceneFileReader* read_file) {
    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::vector<tinyobj::material_t> materials;
    std::string warning, error;
    // Reads `text` in place: a copy would double the memory of a large file.
    struct TextBuffer : std::streambuf {
        explicit TextBuffer(const std::string& text) {
            char* begin = const_cast<char*>(text.data());
            setg(begin, begin, begin + text.size());
        }
    } buffer(text);
    std::istream stream(&buffer);
    std::optional<MtlReader> mtl_reader;
    if (read_file) mtl_reader.emplace(*read_file, name);
    // Fan triangulation below, after checking every index; without a reader `mtllib` is ignored.
    if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warning, &error, &stream,
                          mtl_reader ? &*mtl_reader : nullptr, false, false)) {
        const size_t at = error.rfind("line ");
        const size_t line =
            at == std::string::npos ? 0 : std::strtoul(error.c_str() + at + 5, nullptr, 10);
        Fail(LineSuffix(line),
             "tinyobjloader: " + error.substr(0, error.find_last_not_of("\n ") + 1));
    }
    if (warning.find("Degenerated face") != std::string::npos) {
        // tinyobjloader silently drops faces with fewer than three corners.
        Fail(LineSuffix(FindLine(
                 text,
                 [](const std::vector<std::string>& f) { return f[0] == "f" && f.size() < 4; })),
             "face with fewer than 3 vertices");
    }
    if (mtl_reader && !mtl_reader->failure().empty()) {
        Fail(LineSuffix(FindLine(text,
                                 [&](const std::vector<std::string>& f) {
                                     return f[0] == "mtllib" &&
                                            std::find(f.begin(), f.end(),
                                                      mtl_reader->failed_name()) != f.end();
                                 })),
             mtl_reader->failure());
    }
    if (const size_t at = warning.find("material [ '"); read_file && at != std::string::npos) {
        const std::string material = warning.substr(at + 12, warning.find("' ]", at) - (at + 12));
        Fail(LineSuffix(FindLine(text,
                                 [&](const std::vector<std::string>& f) {
                                     return f[0] == "usemtl" && f.size() > 1 && f[1] == material;
                                 })),
             absl::StrCat("usemtl \"", material, "\": no MTL file of this OBJ defines it"));
    }

    std::vector<Vec3d> positions;
    const std::vector<tinyobj::real_t>& v = attrib.vertices;
    positions.reserve(v.size() / 3);
    for (size_t i = 0; i + 2 < v.size(); i += 3) {
        const Vec3d p(v[i], v[i + 1], v[i + 2]);
        if (!IsFinite(p)) {
            Fail(LineSuffix(FindRecordLine(text, "v", i / 3)),
                 absl::StrCat("vertex ", i / 3 + 1, " is not finite"));
        }
        positions.push_back(p);
    }
    // Unit normals; a zero one (some exporters write them) counts as none.
    std::vector<std::optional<Vec3>> normals;
    for (size_t i = 0; i + 2 < attrib.normals.size(); i += 3) {
        const Vec3 n(attrib.normals[i], attrib.normals[i + 1], attrib.normals[i + 2]);
        if (!IsFinite(n)) {
            Fail(LineSuffix(FindRecordLine(text, "vn", i / 3)),
                 absl::StrCat("normal ", i / 3 + 1, " is not finite"));
        }
        normals.push_back(LengthSquared(n) > 0 ? std::optional(Normalize(n)) : std::nullopt);
    }
    std::vector<Vec2> uvs;
    for (size_t i = 0; i + 1 < attrib.texcoords.size(); i += 2) {
        const Vec2 uv{attrib.texcoords[i], 1 - attrib.texcoords[i + 1]};
        if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) {
            Fail(LineSuffix(FindRecordLine(text, "vt", i / 2)),
                 absl::StrCat("texture coordinate ", i / 2 + 1, " is not finite"));
        }
        uvs.push_back(uv);
    }

    if (positions.empty()) Fail("", "no vertices");
    // First pass: check every index, and find each material's mesh and what it has.
    std::vector<ObjMeshBuilder> builders;
    std::map<int, size_t> builder_of;  // by material id
    size_t face = 0;
    for (const tinyobj::shape_t& shape : shapes) {
        size_t first = 0;
        for (size_t f = 0; f < shape.mesh.num_face_vertices.size(); ++f) {
            const size_t corners = shape.mesh.num_face_vertices[f];
            const int material = read_file ? shape.mesh.material_ids[f] : -1;
            auto [it, added] = builder_of.try_emplace(material, builders.size());
            if (added) {
                builders.emplace_back();
                builders.back().material = material;
                builders.back().first_face = face;
            }
            ObjMeshBuilder& builder = builders[it->second];
            for (size_t c = first; c < first + corners; ++c) {
                const tinyobj::index_t& index = shape.mesh.indices[c];
                // -1 is "not given" for a normal or texture coordinate.
                for (const auto& [i, count, optional, what, plural] :
                     {std::tuple{int64_t(index.vertex_index), positions.size(), false, "vertex",
                                 "vertices"},
                      {int64_t(index.normal_index), normals.size(), true, "normal", "normals"},
                      {int64_t(index.texcoord_index), uvs.size(), true, "texture coordinate",
                       "texture coordinates"}}) {
                    if ((i >= 0 || (optional && i == -1)) && i < int64_t(count)) continue;
                    Fail(LineSuffix(FindRecordLine(text, "f", face, 3)),
                         absl::StrCat("face refers to ", what, " ", i + 1, " but the file has ",
                                      count, " ", plural));
                }
                builder.normals |= index.normal_index >= 0 && normals[index.normal_index];
                builder.uvs |= index.texcoord_index >= 0;
            }
            first += corners;
            ++face;
        }
    }

    if (builders.empty()) Fail("", "no faces");
    // Second pass: one vertex per distinct (position, normal, uv) corner. A corner without a
    // usable normal in a mesh with normals takes its face's normal: its normal index is then
    // -2 - face, its own vertex.
    CornerVertices made(positions.size());
    face = 0;
    for (const tinyobj::shape_t& shape : shapes) {
        size_t first = 0;
        for (size_t f = 0; f < shape.mesh.num_face_vertices.size(); ++f) {
            const size_t corners = shape.mesh.num_face_vertices[f];
            const size_t builder = builder_of.at(read_file ? shape.mesh.material_ids[f] : -1);
            ObjMeshBuilder& b = builders[builder];
            const tinyobj::index_t* corner = &shape.mesh.indices[first];
            // Newell's normal of the polygon, for corners without a normal of their own.
            Vec3d newell;
            for (size_t c = 0; c < corners && b.normals; ++c) {
                const Vec3d& p = positions[corner[c].vertex_index];
                const Vec3d& q = positions[corner[(c + 1) % corners].vertex_index];
                newell += Cross(p, q);
            }
            const Vec3 face_normal =
                LengthSquared(newell) > 0 ? Vec3(Normalize(newell)) : Vec3(0, 0, 1);
            uint32_t vertex[3];
            for (size_t c = 0; c < corners; ++c) {
                const tinyobj::index_t& i = corner[c];
                const bool has_normal = i.normal_index >= 0 && normals[i.normal_index];
                const int64_t n = !b.normals   ? -1
                                  : has_normal ? i.normal_index
                                               : -2 - int64_t(face);
                const int64_t t = b.uvs ? i.texcoord_index : -1;
                int64_t v = made.Find(i.vertex_index, n, t, uint32_t(builder));
                if (v < 0) {
                    v = int64_t(b.mesh.positions.size());
                    made.Add(i.vertex_index, n, t, uint32_t(builder), uint32_t(v));
                    b.mesh.positions.push_back(positions[i.vertex_index]);
                    if (b.normals) {
                        b.mesh.normals.push_back(has_normal ? *normals[i.normal_index]
                                                            : face_normal);
                    }
                    // A corner without one in a mesh with them reads the texel at vt 0 0.
                    if (b.uvs) {
                        b.mesh.uvs.push_back(i.texcoord_index >= 0 ? uvs[i.texcoord_index]
                                                                   : Vec2{0, 1});
                    }
                }
                vertex[std::min<size_t>(c, 2)] = uint32_t(v);
                if (c >= 2) {
                    b.mesh.triangles.push_back({vertex[0], vertex[1], vertex[2]});
                    vertex[1] = vertex[2];
                }
            }
            first += corners;
            ++face;
        }
    }

    MeshFile out;
    std::optional<MtlConverter> converter;
    if (mtl_reader) converter.emplace(*mtl_reader, out);
    for (ObjMeshBuilder& b : builders) {
        if (b.material >= 0) {
            b.mesh.material = int(out.materials.size());
            out.materials.push_back(
                converter->Convert(materials[size_t(b.material)], size_t(b.material)));
        } else {
            b.mesh.material = -1;
            // Only a loader that reads materials needs where faces without one are.
            if (read_file) {
                out.unassigned_where.push_back(
                    absl::StrCat(name, LineSuffix(FindRecordLine(text, "f", b.first_face, 3))));
            }
        }
        out.meshes.push_back(std::move(b.mesh));
    }
    return out;
}

}  // namespace lf::mesh_internal
