#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "mesh_parse.h"

namespace lf::mesh_internal {
namespace {

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };
enum class PlyFormat { kAscii, kLittleEndian, kBigEndian };

std::optional<PlyType> ParsePlyType(std::string_view name) {
    static constexpr std::pair<std::string_view, PlyType> kNames[] = {
        {"char", PlyType::kInt8},      {"int8", PlyType::kInt8},
        {"uchar", PlyType::kUint8},    {"uint8", PlyType::kUint8},
        {"short", PlyType::kInt16},    {"int16", PlyType::kInt16},
        {"ushort", PlyType::kUint16},  {"uint16", PlyType::kUint16},
        {"int", PlyType::kInt32},      {"int32", PlyType::kInt32},
        {"uint", PlyType::kUint32},    {"uint32", PlyType::kUint32},
        {"float", PlyType::kFloat32},  {"float32", PlyType::kFloat32},
        {"double", PlyType::kFloat64}, {"float64", PlyType::kFloat64}};
    for (const auto& [n, type] : kNames) {
        if (n == name) return type;
    }
    return std::nullopt;
}

bool IsInteger(PlyType type) { return type < PlyType::kFloat32; }

struct PlyProperty {
    std::string name;
    PlyType type;                       // of the value, or of each list item
    std::optional<PlyType> count_type;  // set for list properties
};

struct PlyElement {
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

// Reads the body value by value. Errors name the element and record being read, and the line
// for ASCII files.
class PlyBodyReader {
  public:
    PlyBodyReader(std::string_view body, PlyFormat format, size_t first_line)
        : body_(body), format_(format), line_(first_line) {}

    void StartRecord(const std::string& element, uint64_t record) {
        element_ = &element;
        record_ = record;
    }

    [[noreturn]] void Fail(const std::string& message) const {
        mesh_internal::Fail(LineSuffix(format_ == PlyFormat::kAscii ? line_ : 0),
                            absl::StrCat(*element_, " ", record_, ": ", message));
    }

    double Read(PlyType type) {
        const double value = format_ == PlyFormat::kAscii ? ReadAscii() : ReadBinary(type);
        if (IsInteger(type) && value != std::floor(value)) {
            Fail(absl::StrCat("expected an integer, got ", value));
        }
        return value;
    }

  private:
    double ReadAscii() {
        size_t pos = pos_, line = line_;
        while (pos < body_.size() && std::isspace(static_cast<unsigned char>(body_[pos]))) {
            if (body_[pos++] == '\n') ++line;
        }
        // Reported at the last value's line, where the missing ones belong.
        if (pos == body_.size()) Fail("unexpected end of file");
        pos_ = pos;
        line_ = line;
        const char* begin = body_.data() + pos_;
        const char* end = begin;
        while (end < body_.data() + body_.size() &&
               !std::isspace(static_cast<unsigned char>(*end))) {
            ++end;
        }
        pos_ = size_t(end - body_.data());
        double value = 0;
        const auto [stop, error] = std::from_chars(begin, end, value);
        if (error != std::errc() || stop != end) {
            Fail(absl::StrCat("expected a number, got \"", std::string(begin, end), "\""));
        }
        return value;
    }

    double ReadBinary(PlyType type) {
        static constexpr size_t kSizes[] = {1, 1, 2, 2, 4, 4, 4, 8};
        const size_t size = kSizes[int(type)];
        if (body_.size() - pos_ < size) Fail("unexpected end of file");
        unsigned char bytes[8];
        std::memcpy(bytes, body_.data() + pos_, size);
        pos_ += size;
        const PlyFormat native = std::endian::native == std::endian::little
                                     ? PlyFormat::kLittleEndian
                                     : PlyFormat::kBigEndian;
        if (format_ != native) std::reverse(bytes, bytes + size);
        switch (type) {
            case PlyType::kInt8:
                return As<int8_t>(bytes);
            case PlyType::kUint8:
                return As<uint8_t>(bytes);
            case PlyType::kInt16:
                return As<int16_t>(bytes);
            case PlyType::kUint16:
                return As<uint16_t>(bytes);
            case PlyType::kInt32:
                return As<int32_t>(bytes);
            case PlyType::kUint32:
                return As<uint32_t>(bytes);
            case PlyType::kFloat32:
                return As<float>(bytes);
            case PlyType::kFloat64:
                return As<double>(bytes);
        }
        return 0;
    }

    template <typename T>
    static double As(const unsigned char* bytes) {
        T value;
        std::memcpy(&value, bytes, sizeof(T));
        return double(value);
    }

    std::string_view body_;
    PlyFormat format_;
    size_t pos_ = 0;
    size_t line_;
    const std::string* element_ = nullptr;
    uint64_t record_ = 0;
};

// Zero vertex normals (written by some tools for vertices they had no normal for) become the
// area-weighted mean of the normals of the faces around the vertex.
void FillZeroNormals(TriangleMesh& mesh) {
    std::vector<Vec3d> sums;
    for (size_t i = 0; i < mesh.normals.size(); ++i) {
        if (LengthSquared(mesh.normals[i]) > 0) continue;
        if (sums.empty()) {
            sums.resize(mesh.positions.size());
            for (const std::array<uint32_t, 3>& t : mesh.triangles) {
                const Vec3d& a = mesh.positions[t[0]];
                const Vec3d n = Cross(mesh.positions[t[1]] - a, mesh.positions[t[2]] - a);
                for (const uint32_t v : t) sums[v] += n;
            }
        }
        mesh.normals[i] = LengthSquared(sums[i]) > 0 ? Vec3(Normalize(sums[i])) : Vec3(0, 0, 1);
    }
}

}  // namespace

TriangleMesh ParsePly(std::string_view bytes) {
    size_t pos = 0, line = 0;
    auto next_line = [&]() -> std::optional<std::string_view> {
        if (pos >= bytes.size()) return std::nullopt;
        const size_t end = std::min(bytes.find('\n', pos), bytes.size());
        const std::string_view text = bytes.substr(pos, end - pos);
        pos = end + 1;
        ++line;
        return text;
    };
    const std::optional<std::string_view> magic = next_line();
    if (!magic || SplitFields(*magic) != std::vector<std::string>{"ply"}) {
        Fail(":1", "not a PLY file (it must start with a line `ply`)");
    }

    std::optional<PlyFormat> format;
    std::vector<PlyElement> elements;
    bool header_ended = false;
    while (!header_ended) {
        const std::optional<std::string_view> text = next_line();
        if (!text) Fail("", "the header has no end_header line");
        const std::vector<std::string> f = SplitFields(*text);
        const std::string where = LineSuffix(line);
        if (f.empty() || f[0] == "comment" || f[0] == "obj_info") continue;
        if (f[0] == "end_header") {
            header_ended = true;
        } else if (f[0] == "format" && f.size() == 3) {
            if (f[1] == "ascii") {
                format = PlyFormat::kAscii;
            } else if (f[1] == "binary_little_endian") {
                format = PlyFormat::kLittleEndian;
            } else if (f[1] == "binary_big_endian") {
                format = PlyFormat::kBigEndian;
            } else {
                Fail(where, absl::StrCat("unknown format \"", f[1], "\""));
            }
        } else if (f[0] == "element" && f.size() == 3) {
            PlyElement element{f[1], 0, {}};
            const auto [stop, error] =
                std::from_chars(f[2].data(), f[2].data() + f[2].size(), element.count);
            if (error != std::errc() || stop != f[2].data() + f[2].size()) {
                Fail(where, absl::StrCat("bad element count \"", f[2], "\""));
            }
            elements.push_back(std::move(element));
        } else if (f[0] == "property" && !elements.empty() && (f.size() == 3 || f.size() == 5)) {
            const bool list = f.size() == 5;
            if (list && f[1] != "list") Fail(where, "malformed property line");
            PlyProperty property{std::string(f.back()), PlyType::kInt8, std::nullopt};
            const std::optional<PlyType> type = ParsePlyType(f[f.size() - 2]);
            if (!type) Fail(where, absl::StrCat("unknown type \"", f[f.size() - 2], "\""));
            property.type = *type;
            if (list) {
                property.count_type = ParsePlyType(f[2]);
                if (!property.count_type || !IsInteger(*property.count_type)) {
                    Fail(where,
                         absl::StrCat("list length type \"", f[2], "\" is not an integer type"));
                }
            }
            elements.back().properties.push_back(std::move(property));
        } else {
            Fail(where, absl::StrCat("unexpected header line \"", std::string(*text), "\""));
        }
    }
    if (!format) Fail("", "the header has no format line");

    // Property positions of the vertex coordinates and of the face corner list.
    auto find = [](const PlyElement& e, std::string_view name, bool list) {
        for (size_t i = 0; i < e.properties.size(); ++i) {
            if (e.properties[i].name == name && e.properties[i].count_type.has_value() == list) {
                return int(i);
            }
        }
        return -1;
    };
    auto find_corners = [&](const PlyElement& e) {
        return std::max(find(e, "vertex_indices", true), find(e, "vertex_index", true));
    };
    uint64_t vertex_count = 0;
    bool has_vertices = false, has_faces = false;
    for (const PlyElement& e : elements) {
        if (e.name == "vertex") {
            has_vertices = true;
            vertex_count = e.count;
            for (const char* axis : {"x", "y", "z"}) {
                if (find(e, axis, false) < 0) {
                    Fail("", absl::StrCat("vertex element has no property ", axis));
                }
            }
            if (vertex_count > std::numeric_limits<uint32_t>::max()) Fail("", "too many vertices");
        } else if (e.name == "face") {
            has_faces = true;
            const int list = find_corners(e);
            if (list < 0) {
                Fail("", "face element has no list property vertex_indices or vertex_index");
            }
            if (!IsInteger(e.properties[list].type)) {
                Fail("", "face vertex indices are not integers");
            }
        }
    }
    if (!has_vertices) Fail("", "no vertex element");
    if (!has_faces) Fail("", "no face element");

    TriangleMesh mesh;
    PlyBodyReader reader(bytes.substr(std::min(pos, bytes.size())), *format, line + 1);
    std::vector<uint32_t> corners;
    for (const PlyElement& e : elements) {
        if (e.properties.empty()) continue;
        const bool is_vertex = e.name == "vertex", is_face = e.name == "face";
        // Positions of x, y, z, nx, ny, nz, u, v among the element's properties (or -1).
        int slot_of[8] = {find(e, "x", false),
                          find(e, "y", false),
                          find(e, "z", false),
                          find(e, "nx", false),
                          find(e, "ny", false),
                          find(e, "nz", false),
                          -1,
                          -1};
        const bool normals = is_vertex && slot_of[3] >= 0 && slot_of[4] >= 0 && slot_of[5] >= 0;
        if (!normals) slot_of[3] = slot_of[4] = slot_of[5] = -1;
        for (const auto& [u, v] : {std::pair{"u", "v"},
                                   {"s", "t"},
                                   {"texture_u", "texture_v"},
                                   {"texture_s", "texture_t"}}) {
            if (is_vertex && slot_of[6] < 0 && find(e, u, false) >= 0 && find(e, v, false) >= 0) {
                slot_of[6] = find(e, u, false);
                slot_of[7] = find(e, v, false);
            }
        }
        const bool uvs = slot_of[6] >= 0;
        const int corner_list = is_face ? find_corners(e) : -1;
        // A count larger than the file can hold must not turn into a huge allocation.
        if (is_vertex) mesh.positions.reserve(std::min<uint64_t>(e.count, bytes.size()));
        for (uint64_t r = 0; r < e.count; ++r) {
            reader.StartRecord(e.name, r);
            double slot[8] = {};
            corners.clear();
            for (int k = 0; k < int(e.properties.size()); ++k) {
                const PlyProperty& property = e.properties[k];
                if (!property.count_type) {
                    const double value = reader.Read(property.type);
                    for (int a = 0; a < 8; ++a) {
                        if (is_vertex && slot_of[a] == k) slot[a] = value;
                    }
                    continue;
                }
                const double n = reader.Read(*property.count_type);
                if (n < 0) reader.Fail("negative list length");
                for (uint64_t i = 0; i < uint64_t(n); ++i) {
                    const double value = reader.Read(property.type);
                    if (k != corner_list) continue;
                    if (value < 0 || value >= double(vertex_count)) {
                        reader.Fail(absl::StrCat("vertex index ", value, " out of range (",
                                                 vertex_count, " vertices)"));
                    }
                    corners.push_back(uint32_t(value));
                }
            }
            if (is_vertex) {
                const Vec3d p(slot[0], slot[1], slot[2]);
                if (!IsFinite(p)) reader.Fail("coordinate is not finite");
                mesh.positions.push_back(p);
                const Vec3 n{float(slot[3]), float(slot[4]), float(slot[5])};
                if (!IsFinite(n)) reader.Fail("normal is not finite");
                // A zero normal is filled in from the faces around the vertex, below.
                if (normals) mesh.normals.push_back(LengthSquared(n) > 0 ? Normalize(n) : n);
                // Like OBJ's, PLY's v = 0 is the bottom of the image.
                const Vec2 uv{float(slot[6]), float(1 - slot[7])};
                if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) {
                    reader.Fail("texture coordinate is not finite");
                }
                if (uvs) mesh.uvs.push_back(uv);
            }
            if (!is_face) continue;
            if (corners.size() < 3) {
                reader.Fail(
                    absl::StrCat("has ", corners.size(), " vertex indices; need at least 3"));
            }
            for (size_t c = 1; c + 1 < corners.size(); ++c) {
                mesh.triangles.push_back({corners[0], corners[c], corners[c + 1]});
            }
        }
    }
    FillZeroNormals(mesh);
    return mesh;
}

}  // namespace lf::mesh_internal
