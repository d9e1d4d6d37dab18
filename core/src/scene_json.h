// The scene loader's view of its JSON: values with their paths for messages, the number checks
// every part of the scene shares, and the error that unwinds to ParseScene. Private to core.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "lf/core/rgb.h"
#include "lf/core/scene.h"
#include "lf/core/vec.h"

namespace lf::scene_internal {

// Keeps the materials object in file order, which is the order of Scene::materials.
using Json = nlohmann::ordered_json;

inline constexpr int kMaxResolution = 65536;
inline constexpr int64_t kMaxPixels = int64_t(1) << 28;
inline constexpr float kMaxFloat = std::numeric_limits<float>::max();

// Validation runs many levels deep; an error unwinds to ParseScene as this exception, which adds
// the source name, so every check stays one line.
struct LoadError {
    absl::Status status;
};

// `text` as JSON, or an error naming `source` and the line and column of the fault.
absl::Status ParseJson(const std::string& text, const std::string& source, Json& root);

// A value's type, and the value itself for strings and numbers, for messages.
std::string Describe(const Json& json);

// A JSON value with its path from the root (`shapes[2].vertices[1]`), for messages.
class Node {
  public:
    Node(const Json& json, std::string path, std::vector<std::string>* warnings)
        : json_(json), path_(std::move(path)), warnings_(warnings) {}

    const Json& json() const { return json_; }
    const std::string& path() const { return path_; }

    [[noreturn]] void Fail(const std::string& message) const {
        throw LoadError{absl::InvalidArgumentError(
            path_.empty() ? std::string(message) : absl::StrCat(path_, ": ", message))};
    }

    void RequireObject() const {
        if (!json_.is_object()) Fail(absl::StrCat("expected an object, got ", Describe(json_)));
    }

    // Unknown keys are most likely typos, but they do not make the scene unusable.
    // `also`: keys every object of a kind shares (a material's emission keys).
    void WarnUnknownKeys(std::initializer_list<std::string_view> known,
                         std::span<const std::string_view> also = {}) const {
        for (const auto& [key, value] : json_.items()) {
            if (std::find(known.begin(), known.end(), key) == known.end() &&
                std::find(also.begin(), also.end(), key) == also.end()) {
                warnings_->push_back(absl::StrCat(Child(key), ": unknown key, ignored"));
            }
        }
    }

    // For objects where a misspelt key would silently change the result: an unknown key is an
    // error, `what` saying what has which keys ("a homogeneous medium has type, sigma_a, ...").
    void RejectUnknownKeys(std::initializer_list<std::string_view> known,
                           const std::string& what) const {
        RequireObject();
        for (const auto& [key, value] : json_.items()) {
            if (std::find(known.begin(), known.end(), key) == known.end()) {
                Fail(absl::StrCat("unknown key \"", key, "\"; ", what));
            }
        }
    }

    void ExpectObject(std::initializer_list<std::string_view> known) const {
        RequireObject();
        WarnUnknownKeys(known);
    }

    bool Has(const std::string& key) const { return json_.contains(key); }

    std::optional<Node> Find(const std::string& key) const {
        if (!json_.contains(key)) return std::nullopt;
        return Node(json_.at(key), Child(key), warnings_);
    }

    Node Get(const std::string& key) const {
        if (!json_.contains(key)) Fail(absl::StrCat("missing required key \"", key, "\""));
        return Node(json_.at(key), Child(key), warnings_);
    }

    // The elements of an array; `count`, when given, is required.
    std::vector<Node> Elements(std::optional<size_t> count = std::nullopt) const {
        if (!json_.is_array()) Fail(absl::StrCat("expected an array, got ", Describe(json_)));
        if (count && json_.size() != *count) {
            Fail(absl::StrCat("expected ", *count, " elements, got ", json_.size()));
        }
        std::vector<Node> elements;
        for (size_t i = 0; i < json_.size(); ++i) {
            elements.emplace_back(json_[i], absl::StrCat(path_, "[", i, "]"), warnings_);
        }
        return elements;
    }

    std::string String() const {
        if (!json_.is_string()) Fail(absl::StrCat("expected a string, got ", Describe(json_)));
        return json_.get<std::string>();
    }

    // One of `choices`, by its spelling in the file; anything else is an error naming `what`
    // and listing the spellings ("expected a, b or c").
    template <typename T>
    T OneOf(std::string_view what,
            std::initializer_list<std::pair<std::string_view, T>> choices) const {
        const std::string name = String();
        std::string expected;
        size_t i = 0;
        for (const auto& [spelling, value] : choices) {
            if (spelling == name) return value;
            expected += absl::StrCat(i == 0                    ? ""
                                     : i + 1 == choices.size() ? " or "
                                                               : ", ",
                                     std::string(spelling));
            ++i;
        }
        Fail(absl::StrCat("unknown ", std::string(what), " \"", name, "\"; expected ", expected));
    }

    bool Bool() const {
        if (!json_.is_boolean())
            Fail(absl::StrCat("expected true or false, got ", Describe(json_)));
        return json_.get<bool>();
    }

    double Number() const {
        if (!json_.is_number()) Fail(absl::StrCat("expected a number, got ", Describe(json_)));
        const double value = json_.get<double>();
        if (!std::isfinite(value)) Fail("not a finite number");
        return value;
    }

    double NumberIn(double lo, double hi, const std::string& range) const {
        const double value = Number();
        if (!(value >= lo && value <= hi)) Fail(absl::StrCat("must be ", range, ", got ", value));
        return value;
    }

    // A number in (0, kMaxFloat]: the kernels keep material parameters in float.
    float PositiveFloat() const {
        const double value = Number();
        if (!(value > 0 && value <= kMaxFloat)) {
            Fail(absl::StrCat("must be a positive float, got ", value));
        }
        return float(value);
    }

    int Integer(int lo, int hi) const {
        const double value = NumberIn(lo, hi, absl::StrCat("an integer in [", lo, ", ", hi, "]"));
        if (value != std::floor(value)) Fail(absl::StrCat("must be an integer, got ", value));
        return int(value);
    }

    double Coordinate() const { return NumberIn(-kMaxCoordinate, kMaxCoordinate, "within ±1e15"); }

    // [x, y, z], each a Coordinate().
    Vec3d Vector() const {
        const std::vector<Node> e = Elements(3);
        return {e[0].Coordinate(), e[1].Coordinate(), e[2].Coordinate()};
    }

    // [r, g, b], each in [0, max].
    Rgb Color(float max) const {
        const std::vector<Node> e = Elements(3);
        const std::string range = max == 1           ? "in [0, 1]"
                                  : max == kMaxFloat ? "≥ 0 and below 3.4e38 (float range)"
                                                     : absl::StrCat("≥ 0 and at most ", max);
        return {float(e[0].NumberIn(0, max, range)), float(e[1].NumberIn(0, max, range)),
                float(e[2].NumberIn(0, max, range))};
    }

  private:
    std::string Child(const std::string& key) const {
        return path_.empty() ? std::string(key) : absl::StrCat(path_, ".", key);
    }

    const Json& json_;
    std::string path_;
    std::vector<std::string>* warnings_;
};

}  // namespace lf::scene_internal
