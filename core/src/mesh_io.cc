#include "lf/core/mesh_io.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <string_view>
#include <vector>

#include "absl/strings/str_cat.h"
#include "lf/core/file_util.h"

namespace lf {
namespace {

// Parsers run deep loops; an error unwinds to LoadMesh as this exception, which adds the file
// name. `where` is ":LINE" when the line is known, otherwise empty.
struct MeshError {
    std::string where;
    std::string message;
};

[[noreturn]] void Fail(std::string where, std::string message) {
    throw MeshError{std::move(where), std::move(message)};
}

std::string LineSuffix(size_t line) { return line > 0 ? absl::StrCat(":", line) : ""; }

std::vector<std::string> SplitFields(std::string_view line) {
    std::vector<std::string> fields;
    size_t pos = 0;
    while ((pos = line.find_first_not_of(" \t\r", pos)) != std::string_view::npos) {
        const size_t end = std::min(line.find_first_of(" \t\r", pos), line.size());
        fields.emplace_back(line.substr(pos, end - pos));
        pos = end;
    }
    return fields;
}

// ---- Wavefront OBJ ---------------------------------------------------------------------------

// tinyobjloader does not say which line a face or vertex came from. On an error this finds the
// line of the first record with `keyword` for which visit(number of fields) returns true.
template <typename Visit>
size_t FindObjLine(std::string_view text, std::string_view keyword, Visit visit) {
    size_t line = 0, pos = 0;
    while (pos < text.size()) {
        // Line ends as tinyobjloader counts them: \n, \r\n or a lone \r.
        const size_t end = std::min(text.find_first_of("\r\n", pos), text.size());
        const std::vector<std::string> fields = SplitFields(text.substr(pos, end - pos));
        ++line;
        pos = end + (text.substr(end, 2) == "\r\n" ? 2 : 1);
        if (!fields.empty() && fields[0] == keyword && visit(fields.size() - 1)) return line;
    }
    return 0;
}

TriangleMesh ParseObj(const std::string& text) {
    tinyobj::ObjReaderConfig config;
    config.triangulate = false;  // fan triangulation below, after checking every index
    config.vertex_color = false;
    tinyobj::ObjReader reader;
    // Materials belong in the scene file, so `mtllib` is ignored.
    if (!reader.ParseFromString(text, "", config)) {
        const std::string& error = reader.Error();
        const size_t at = error.rfind("line ");
        const size_t line =
            at == std::string::npos ? 0 : std::strtoul(error.c_str() + at + 5, nullptr, 10);
        Fail(LineSuffix(line),
             "tinyobjloader: " + error.substr(0, error.find_last_not_of("\n ") + 1));
    }
    if (reader.Warning().find("Degenerated face") != std::string::npos) {
        // tinyobjloader silently drops faces with fewer than three corners.
        Fail(LineSuffix(FindObjLine(text, "f", [](size_t n) { return n < 3; })),
             "face with fewer than 3 vertices");
    }

    TriangleMesh mesh;
    const std::vector<tinyobj::real_t>& v = reader.GetAttrib().vertices;
    mesh.positions.reserve(v.size() / 3);
    for (size_t i = 0; i + 2 < v.size(); i += 3) {
        const Vec3d p(v[i], v[i + 1], v[i + 2]);
        if (!IsFinite(p)) {
            size_t seen = 0;
            const size_t line = FindObjLine(text, "v", [&](size_t) { return seen++ == i / 3; });
            Fail(LineSuffix(line), absl::StrCat("vertex ", i / 3 + 1, " is not finite"));
        }
        mesh.positions.push_back(p);
    }

    const int64_t vertex_count = int64_t(mesh.positions.size());
    size_t face = 0;
    for (const tinyobj::shape_t& shape : reader.GetShapes()) {
        const std::vector<tinyobj::index_t>& indices = shape.mesh.indices;
        size_t first = 0;
        for (const unsigned int corners : shape.mesh.num_face_vertices) {
            for (size_t c = first; c < first + corners; ++c) {
                const int64_t index = indices[c].vertex_index;
                if (index < 0 || index >= vertex_count) {
                    size_t seen = 0;
                    const size_t line =
                        FindObjLine(text, "f", [&](size_t n) { return n >= 3 && seen++ == face; });
                    Fail(LineSuffix(line),
                         absl::StrCat("face refers to vertex ", index + 1, " but the file has ",
                                      vertex_count, " vertices"));
                }
            }
            for (size_t c = first + 1; c + 1 < first + corners; ++c) {
                mesh.triangles.push_back({uint32_t(indices[first].vertex_index),
                                          uint32_t(indices[c].vertex_index),
                                          uint32_t(indices[c + 1].vertex_index)});
            }
            first += corners;
            ++face;
        }
    }
    return mesh;
}

// ---- PLY -------------------------------------------------------------------------------------

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
        lf::Fail(LineSuffix(format_ == PlyFormat::kAscii ? line_ : 0),
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
        const int axes[3] = {find(e, "x", false), find(e, "y", false), find(e, "z", false)};
        const int corner_list = is_face ? find_corners(e) : -1;
        // A count larger than the file can hold must not turn into a huge allocation.
        if (is_vertex) mesh.positions.reserve(std::min<uint64_t>(e.count, bytes.size()));
        for (uint64_t r = 0; r < e.count; ++r) {
            reader.StartRecord(e.name, r);
            Vec3d p;
            corners.clear();
            for (int k = 0; k < int(e.properties.size()); ++k) {
                const PlyProperty& property = e.properties[k];
                if (!property.count_type) {
                    const double value = reader.Read(property.type);
                    for (int a = 0; a < 3; ++a) {
                        if (is_vertex && axes[a] == k) p[a] = value;
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
                if (!IsFinite(p)) reader.Fail("coordinate is not finite");
                mesh.positions.push_back(p);
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
    return mesh;
}

}  // namespace

absl::StatusOr<TriangleMesh> ParseMesh(const std::string& bytes, const std::string& name) {
    std::string extension = std::filesystem::path(name).extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    if (extension != ".obj" && extension != ".ply") {
        return absl::InvalidArgumentError(absl::StrCat(name, ": unknown mesh format \"", extension,
                                                       "\" (expected .obj or .ply)"));
    }
    try {
        TriangleMesh mesh = extension == ".obj" ? ParseObj(bytes) : ParsePly(bytes);
        if (mesh.positions.empty()) Fail("", "no vertices");
        if (mesh.triangles.empty()) Fail("", "no faces");
        mesh.name = std::filesystem::path(name).stem().string();
        return mesh;
    } catch (const MeshError& e) {
        return absl::InvalidArgumentError(absl::StrCat(name, e.where, ": ", e.message));
    }
}

absl::StatusOr<TriangleMesh> LoadMesh(const std::string& path) {
    absl::StatusOr<std::string> bytes = ReadFile(path);
    if (!bytes.ok()) return bytes.status();
    return ParseMesh(*bytes, path);
}

}  // namespace lf
