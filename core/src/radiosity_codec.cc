#include "lf/core/radiosity_codec.h"

#include <bit>
#include <cstring>

#include "absl/strings/str_cat.h"

namespace lf {

// The values are copied as they lie in memory.
static_assert(std::endian::native == std::endian::little);

namespace {

constexpr uint32_t kVersion = 1;
// A billion unknowns is far beyond any mesh; the bound keeps a corrupt count from asking for
// terabytes.
constexpr uint32_t kMaxCount = uint32_t(1) << 30;

template <typename T>
void Put(std::string& out, const T& v) {
    out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

void PutRgbs(std::string& out, std::span<const Rgb> values) {
    for (const Rgb& c : values) {
        Put(out, c.r);
        Put(out, c.g);
        Put(out, c.b);
    }
}

class Reader {
  public:
    Reader(std::string_view bytes, const char* what) : bytes_(bytes), what_(what) {}

    absl::Status Magic(const char (&magic)[5]) {
        if (bytes_.size() < 8 || bytes_.substr(0, 4) != std::string_view(magic, 4)) {
            return absl::InvalidArgumentError(absl::StrCat(what_, ": not an encoding of one"));
        }
        bytes_.remove_prefix(4);
        uint32_t version = 0;
        Get(version);
        if (version != kVersion) {
            return absl::InvalidArgumentError(
                absl::StrCat(what_, ": version ", version, ", expected ", kVersion));
        }
        return absl::OkStatus();
    }
    template <typename T>
    bool Get(T& v) {
        if (bytes_.size() < sizeof(T)) return ok_ = false;
        std::memcpy(&v, bytes_.data(), sizeof(T));
        bytes_.remove_prefix(sizeof(T));
        return true;
    }
    // Reads a count, refusing one the remaining bytes cannot hold.
    bool Count(int64_t& n, size_t bytes_each) {
        uint32_t v = 0;
        if (!Get(v) || v > kMaxCount || bytes_.size() / bytes_each < v) return ok_ = false;
        n = v;
        return true;
    }
    std::vector<Rgb> Rgbs(int64_t n) {
        std::vector<Rgb> values(static_cast<size_t>(n));
        for (Rgb& c : values) Get(c.r), Get(c.g), Get(c.b);
        return values;
    }
    bool empty() const { return bytes_.empty(); }
    bool ok() const { return ok_; }
    absl::Status Done() const {
        if (!ok_) return absl::InvalidArgumentError(absl::StrCat(what_, ": truncated"));
        if (!bytes_.empty()) {
            return absl::InvalidArgumentError(
                absl::StrCat(what_, ": ", bytes_.size(), " bytes after the end"));
        }
        return absl::OkStatus();
    }

  private:
    std::string_view bytes_;
    const char* what_;
    bool ok_ = true;
};

}  // namespace

std::string EncodeRadiosity(std::span<const Rgb> radiosity) {
    std::string out("LFRB");
    Put(out, kVersion);
    Put(out, uint32_t(radiosity.size()));
    PutRgbs(out, radiosity);
    return out;
}

absl::StatusOr<std::vector<Rgb>> DecodeRadiosity(std::string_view bytes) {
    Reader in(bytes, "radiosity vector");
    if (absl::Status s = in.Magic("LFRB"); !s.ok()) return s;
    int64_t n = 0;
    std::vector<Rgb> values;
    if (in.Count(n, 3 * sizeof(float))) values = in.Rgbs(n);
    if (absl::Status s = in.Done(); !s.ok()) return s;
    return values;
}

std::string EncodeSweepResult(const SweepChunkResult& r) {
    std::string out("LFSW");
    Put(out, kVersion);
    for (int32_t v : {r.sweep, r.chunk, r.sides, r.side_begin, int32_t(r.input.size()),
                      int32_t(r.change.size())}) {
        Put(out, v);
    }
    for (size_t g = 0; g < r.change.size(); ++g) {
        Put(out, r.change[g]);
        Put(out, r.power[g]);
    }
    PutRgbs(out, r.input);
    PutRgbs(out, r.output);
    return out;
}

namespace {

// One result from where `in` stands.
absl::StatusOr<SweepChunkResult> ReadSweepResult(Reader& in) {
    if (absl::Status s = in.Magic("LFSW"); !s.ok()) return s;
    SweepChunkResult r;
    int64_t side_count = 0, groups = 0;
    if (in.Get(r.sweep) && in.Get(r.chunk) && in.Get(r.sides) && in.Get(r.side_begin) &&
        in.Count(side_count, 6 * sizeof(float)) && in.Count(groups, 2 * sizeof(double))) {
        r.change.resize(size_t(groups));
        r.power.resize(size_t(groups));
        for (int64_t g = 0; g < groups; ++g)
            in.Get(r.change[size_t(g)]), in.Get(r.power[size_t(g)]);
        r.input = in.Rgbs(side_count);
        r.output = in.Rgbs(side_count);
    }
    if (r.sweep < 0 || r.chunk < 0 || r.side_begin < 0 || r.sides < 0 ||
        int64_t(r.side_begin) + side_count > r.sides) {
        return absl::InvalidArgumentError(absl::StrCat(
            "sweep result: sides [", r.side_begin, ", ", r.side_begin + side_count,
            ") outside the system's ", r.sides, " (sweep ", r.sweep, ", chunk ", r.chunk, ")"));
    }
    return r;
}

}  // namespace

std::string EncodeSweepResults(std::span<const SweepChunkResult> results) {
    std::string out;
    for (const SweepChunkResult& r : results) out += EncodeSweepResult(r);
    return out;
}

absl::StatusOr<std::vector<SweepChunkResult>> DecodeSweepResults(std::string_view bytes,
                                                                 size_t max_results) {
    Reader in(bytes, "sweep result");
    std::vector<SweepChunkResult> results;
    do {
        // A record can be 32 bytes and decode to several times that: bounded before decoding.
        if (results.size() == max_results) {
            return absl::InvalidArgumentError(absl::StrCat("sweep result: more than ", max_results,
                                                           " chunk results in one task's"));
        }
        absl::StatusOr<SweepChunkResult> r = ReadSweepResult(in);
        if (!in.ok()) return in.Done();  // truncated
        if (!r.ok() && !results.empty()) {
            return absl::InvalidArgumentError(
                absl::StrCat("after ", results.size(), " chunk results: ", r.status().message()));
        }
        if (!r.ok()) return r.status();
        results.push_back(std::move(*r));
    } while (!in.empty());
    return results;
}

}  // namespace lf
