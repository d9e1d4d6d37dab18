#include "lf/core/texture_io.h"

#include <ImfIO.h>
#include <ImfRgbaFile.h>
#include <openssl/evp.h>
#include <stb_image.h>

#include <cmath>
#include <cstring>
#include <exception>
#include <map>
#include <mutex>
#include <optional>
#include <string_view>

#include "absl/strings/str_cat.h"
#include "lf/core/log.h"

namespace lf {
namespace {

bool IsExr(const std::string& bytes) {
    return bytes.size() >= 4 && std::memcmp(bytes.data(), "\x76\x2f\x31\x01", 4) == 0;
}

absl::Status CheckSize(const std::string& name, int64_t width, int64_t height) {
    if (width < 1 || height < 1 || width > kMaxTextureSide || height > kMaxTextureSide ||
        width * height > kMaxTextureTexels) {
        return absl::InvalidArgumentError(absl::StrCat(name, ": image of ", width, " x ", height,
                                                       " texels; at most ", kMaxTextureSide,
                                                       " on a side and 2^28 in all are accepted"));
    }
    return absl::OkStatus();
}

// Half floats and RGBE can hold infinities and NaNs; as texels they would poison every path
// that reads them, so they read as 0.
void ZeroNonFinite(std::vector<float>& texels) {
    for (float& t : texels) {
        if (!std::isfinite(t)) t = 0;
    }
}

// OpenEXR reads through an IStream; this one serves the file's bytes from memory.
class MemoryStream : public Imf::IStream {
  public:
    MemoryStream(const std::string& bytes, const std::string& name)
        : Imf::IStream(name.c_str()), bytes_(bytes) {}

    bool read(char c[], int n) override {
        if (n < 0 || uint64_t(n) > bytes_.size() - position_) {
            throw std::runtime_error("unexpected end of file");
        }
        std::memcpy(c, bytes_.data() + position_, size_t(n));
        position_ += uint64_t(n);
        return position_ < bytes_.size();
    }
    uint64_t tellg() override { return position_; }
    void seekg(uint64_t pos) override { position_ = std::min<uint64_t>(pos, bytes_.size()); }

  private:
    const std::string& bytes_;
    uint64_t position_ = 0;
};

// OpenEXR allocates an attribute of a type it does not know at the size the header declares,
// before reading it: a 1.5 KB file declaring a 1.4 GB attribute (found by tests/fuzz) made it
// allocate 1.4 GB. So every header's attribute sizes must fit in the file before OpenEXR sees
// it. A header cut short is left to OpenEXR's message.
absl::Status CheckExrHeaders(const std::string& bytes, const std::string& name) {
    const bool multipart = bytes.size() >= 8 && (uint8_t(bytes[5]) & 0x10) != 0;  // flag bit 12
    size_t at = 8;
    // A NUL-terminated string at `at`, or nullopt where the file ends first.
    auto text = [&]() -> std::optional<std::string_view> {
        const size_t end = bytes.find('\0', at);
        if (end == std::string::npos) return std::nullopt;
        const std::string_view s(bytes.data() + at, end - at);
        at = end + 1;
        return s;
    };
    auto le32 = [&](size_t i) {
        uint32_t v;
        std::memcpy(&v, bytes.data() + i, 4);
        return int32_t(v);
    };
    for (bool empty = false; !empty;) {  // a multipart file's headers end with an empty one
        empty = true;
        while (true) {
            const std::optional<std::string_view> attribute = text();
            if (!attribute) return absl::OkStatus();
            if (attribute->empty()) break;
            empty = false;
            const std::optional<std::string_view> type = text();
            if (!type || bytes.size() - at < 4) return absl::OkStatus();
            const int32_t size = le32(at);
            at += 4;
            if (size < 0 || size_t(size) > bytes.size() - at) {
                return absl::InvalidArgumentError(
                    absl::StrCat(name, ": not a readable OpenEXR image: header attribute \"",
                                 LogSafe(std::string(*attribute), 64), "\" declares ", size,
                                 " bytes, the file has ", bytes.size() - at, " left"));
            }
            at += size_t(size);
        }
        if (!multipart) break;
    }
    return absl::OkStatus();
}

absl::StatusOr<TextureImage> DecodeExr(const std::string& bytes, const std::string& name) {
    if (absl::Status s = CheckExrHeaders(bytes, name); !s.ok()) return s;
    try {
        MemoryStream stream(bytes, name);
        Imf::RgbaInputFile file(stream);
        const Imath::Box2i window = file.dataWindow();
        const int64_t width = int64_t(window.max.x) - window.min.x + 1;
        const int64_t height = int64_t(window.max.y) - window.min.y + 1;
        if (absl::Status s = CheckSize(name, width, height); !s.ok()) return s;
        std::vector<Imf::Rgba> pixels(size_t(width * height));
        // The frame buffer is addressed by absolute data-window coordinates.
        file.setFrameBuffer(pixels.data() - window.min.x - window.min.y * width, 1, size_t(width));
        file.readPixels(window.min.y, window.max.y);
        TextureImage image;
        image.width = int(width);
        image.height = int(height);
        image.hdr = true;
        const bool alpha = (file.channels() & Imf::WRITE_A) != 0;
        image.channels = alpha ? 4 : 3;
        image.texels32.reserve(pixels.size() * size_t(image.channels));
        for (const Imf::Rgba& p : pixels) {
            image.texels32.insert(image.texels32.end(), {float(p.r), float(p.g), float(p.b)});
            if (alpha) image.texels32.push_back(float(p.a));
        }
        ZeroNonFinite(image.texels32);
        return image;
    } catch (const std::exception& e) {
        return absl::InvalidArgumentError(
            absl::StrCat(name, ": not a readable OpenEXR image: ", e.what()));
    }
}

// The formats stb_image decodes for us, by their magic numbers (stb_image's own tests for
// them), each with the most texels a byte of a file of it may claim. A truncated JPEG or HDR
// decodes in full (stb_image reads zeros past the end), so a few hundred bytes could claim
// gigabytes of texels. No valid file packs more than about 8,300 texels into a byte of PNG (1 bit
// a texel at deflate's limit of 1032:1), 460 of JPEG (one 1-bit DC code a block, 4x4 chroma
// subsampling) or 16 of Radiance HDR (runs of 127 in 8 bytes): about twice those are the bounds.
struct StbFormat {
    std::string_view magic;
    int64_t texels_per_byte;
};
constexpr StbFormat kStbFormats[] = {
    {"\x89PNG\r\n\x1a\n", 16384}, {"\xff\xd8", 1024}, {"#?RADIANCE\n", 32}, {"#?RGBE\n", 32}};

const StbFormat* FindStbFormat(const std::string& bytes) {
    for (const StbFormat& format : kStbFormats) {
        if (std::string_view(bytes).starts_with(format.magic)) return &format;
    }
    return nullptr;
}

// A PNG's size from its IHDR chunk. stb_image refuses very large images itself, with a message
// about the format rather than the size; this keeps the size the reason given.
int64_t BigEndian32(const std::string& bytes, size_t at) {
    int64_t v = 0;
    for (size_t i = 0; i < 4; ++i) v = v << 8 | static_cast<unsigned char>(bytes[at + i]);
    return v;
}

std::optional<std::pair<int64_t, int64_t>> PngSize(const std::string& bytes) {
    if (bytes.size() < 24 || bytes.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0 ||
        bytes.compare(12, 4, "IHDR") != 0) {
        return std::nullopt;
    }
    return std::pair(BigEndian32(bytes, 16), BigEndian32(bytes, 20));
}

// A PNG's chunks up to IEND, each within the file: stb_image (the copy Debian's libdraco
// exports too) allocates what a chunk claims before reading it, up to 2 GB for 247 bytes.
absl::Status CheckPngChunks(const std::string& bytes, const std::string& name) {
    for (size_t at = 8; at + 12 <= bytes.size();) {
        const int64_t length = BigEndian32(bytes, at);
        if (length > int64_t(bytes.size() - at - 12)) {
            return absl::InvalidArgumentError(absl::StrCat(
                name, ": PNG chunk at byte ", at, " claims ", length, " bytes, beyond the file's ",
                bytes.size(), " (truncated or corrupt)"));
        }
        if (bytes.compare(at + 4, 4, "IEND") == 0) break;
        at += 12 + size_t(length);
    }
    return absl::OkStatus();
}

absl::StatusOr<TextureImage> DecodeStb(const std::string& bytes, const std::string& name) {
    const auto* data = reinterpret_cast<const stbi_uc*>(bytes.data());
    // stb_image takes an int length; no image file of 2 GB would pass the size check anyway.
    if (bytes.size() > size_t(std::numeric_limits<int>::max())) {
        return absl::InvalidArgumentError(absl::StrCat(name, ": image file above 2 GB"));
    }
    if (const auto size = PngSize(bytes)) {
        if (absl::Status s = CheckSize(name, size->first, size->second); !s.ok()) return s;
        if (absl::Status s = CheckPngChunks(bytes, name); !s.ok()) return s;
    }
    const int length = int(bytes.size());
    int width = 0, height = 0, channels = 0;
    // Debian's stb_image is built with every format; TGA, BMP, PSD, GIF, PIC and PNM (TGA has no
    // magic number, so almost any bytes parse as one) are not ours to accept.
    const StbFormat* format = FindStbFormat(bytes);
    if (!format || !stbi_info_from_memory(data, length, &width, &height, &channels)) {
        return absl::InvalidArgumentError(
            absl::StrCat(name, ": not a PNG, JPEG, HDR or EXR image (",
                         format ? stbi_failure_reason() : "unknown signature", ")"));
    }
    // From the header alone, before a byte of texels is allocated.
    if (absl::Status s = CheckSize(name, width, height); !s.ok()) return s;
    if (int64_t(width) * height > format->texels_per_byte * int64_t(bytes.size())) {
        return absl::InvalidArgumentError(
            absl::StrCat(name, ": image of ", width, " x ", height, " texels in a file of ",
                         bytes.size(), " bytes: more than a valid file can hold (truncated?)"));
    }
    TextureImage image;
    const size_t count = size_t(width) * size_t(height);
    auto fail = [&] {
        return absl::InvalidArgumentError(
            absl::StrCat(name, ": corrupt image data (", stbi_failure_reason(), ")"));
    };
    if (stbi_is_hdr_from_memory(data, length)) {
        float* texels = stbi_loadf_from_memory(data, length, &width, &height, &channels, 0);
        if (!texels) return fail();
        image.texels32.assign(texels, texels + count * size_t(channels));
        stbi_image_free(texels);
        ZeroNonFinite(image.texels32);
        image.hdr = true;
    } else if (stbi_is_16_bit_from_memory(data, length)) {
        stbi_us* texels = stbi_load_16_from_memory(data, length, &width, &height, &channels, 0);
        if (!texels) return fail();
        image.texels32.resize(count * size_t(channels));
        for (size_t i = 0; i < image.texels32.size(); ++i) {
            image.texels32[i] = float(texels[i]) / 65535.0f;
        }
        stbi_image_free(texels);
    } else {
        stbi_uc* texels = stbi_load_from_memory(data, length, &width, &height, &channels, 0);
        if (!texels) return fail();
        image.texels8.assign(texels, texels + count * size_t(channels));
        stbi_image_free(texels);
    }
    image.width = width;
    image.height = height;
    image.channels = channels;
    return image;
}

std::string Sha256(const std::string& bytes) {
    unsigned char digest[EVP_MAX_MD_SIZE];
    unsigned int size = 0;
    EVP_Digest(bytes.data(), bytes.size(), digest, &size, EVP_sha256(), nullptr);
    return std::string(reinterpret_cast<const char*>(digest), size);
}

// Decoded images by the SHA-256 of their file, held weakly: an image lives as long as a scene
// uses it, and a second scene (or job, on a worker) loading the same file while it lives shares
// it.
struct TextureCache {
    std::mutex mutex;
    std::map<std::string, std::weak_ptr<const TextureImage>> images;
};

TextureCache& Cache() {
    static TextureCache cache;
    return cache;
}

}  // namespace

absl::StatusOr<std::shared_ptr<const TextureImage>> DecodeTexture(const std::string& bytes,
                                                                  const std::string& name) {
    const std::string key = Sha256(bytes);
    TextureCache& cache = Cache();
    {
        const std::lock_guard<std::mutex> lock(cache.mutex);
        if (const auto it = cache.images.find(key); it != cache.images.end()) {
            if (std::shared_ptr<const TextureImage> image = it->second.lock()) return image;
        }
    }
    absl::StatusOr<TextureImage> decoded =
        IsExr(bytes) ? DecodeExr(bytes, name) : DecodeStb(bytes, name);
    if (!decoded.ok()) return decoded.status();
    decoded->name = name;
    auto image = std::make_shared<const TextureImage>(*std::move(decoded));
    const std::lock_guard<std::mutex> lock(cache.mutex);
    std::weak_ptr<const TextureImage>& slot = cache.images[key];
    // Another thread may have decoded the same file meanwhile: keep one copy.
    if (std::shared_ptr<const TextureImage> existing = slot.lock()) return existing;
    std::erase_if(cache.images, [](const auto& entry) { return entry.second.expired(); });
    cache.images[key] = image;
    return image;
}

}  // namespace lf
