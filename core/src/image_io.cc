#include "lf/core/image_io.h"

#include <ImfAttribute.h>
#include <ImfChannelList.h>
#include <ImfChromaticitiesAttribute.h>
#include <ImfDoubleAttribute.h>
#include <ImfFloatAttribute.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfIntAttribute.h>
#include <ImfOutputFile.h>
#include <ImfStandardAttributes.h>
#include <ImfStringAttribute.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <exception>
#include <vector>

namespace lf {

// OpenEXR reports errors by exception; this adapter turns them into status values.

absl::Status WriteExr(const std::string& path, const Image& image,
                      const ExrAttributes& attributes) {
    try {
        Imf::Header header(image.width(), image.height());
        header.compression() = Imf::ZIP_COMPRESSION;
        for (const auto& [name, value] : attributes) {
            if (const auto* s = std::get_if<std::string>(&value)) {
                header.insert(name, Imf::StringAttribute(*s));
            } else if (const auto* i = std::get_if<int>(&value)) {
                header.insert(name, Imf::IntAttribute(*i));
            } else if (const auto* d = std::get_if<double>(&value)) {
                header.insert(name, Imf::DoubleAttribute(*d));
            } else if (const auto* f = std::get_if<float>(&value)) {
                header.insert(name, Imf::FloatAttribute(*f));
            } else {
                const auto& c = std::get<ExrChromaticities>(value);
                header.insert(name, Imf::ChromaticitiesAttribute(Imf::Chromaticities(
                                        {c.red_x, c.red_y}, {c.green_x, c.green_y},
                                        {c.blue_x, c.blue_y}, {c.white_x, c.white_y})));
            }
        }
        Imf::FrameBuffer frame;
        for (const auto& [name, data] : image.channels()) {
            header.channels().insert(name, Imf::Channel(Imf::FLOAT));
            frame.insert(name, Imf::Slice(Imf::FLOAT, (char*)data.data(), sizeof(float),
                                          sizeof(float) * size_t(image.width())));
        }
        Imf::OutputFile file(path.c_str(), header);
        file.setFrameBuffer(frame);
        file.writePixels(image.height());
    } catch (const std::exception& e) {
        return absl::UnavailableError(path + ": cannot write EXR: " + e.what());
    }
    return absl::OkStatus();
}

absl::StatusOr<ExrFile> ReadExr(const std::string& path) {
    try {
        Imf::InputFile file(path.c_str());
        const Imath::Box2i dw = file.header().dataWindow();
        const int width = dw.max.x - dw.min.x + 1, height = dw.max.y - dw.min.y + 1;
        ExrFile out{Image(width, height), {}};
        Imf::FrameBuffer frame;
        for (auto it = file.header().channels().begin(); it != file.header().channels().end();
             ++it) {
            std::vector<float>& data = out.image.Channel(it.name());
            char* base = (char*)(data.data()) -
                         (size_t(dw.min.x) + size_t(dw.min.y) * width) * sizeof(float);
            frame.insert(it.name(), Imf::Slice(Imf::FLOAT, base, sizeof(float),
                                               sizeof(float) * size_t(width)));
        }
        file.setFrameBuffer(frame);
        file.readPixels(dw.min.y, dw.max.y);
        for (auto it = file.header().begin(); it != file.header().end(); ++it) {
            if (const auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute())) {
                out.attributes[it.name()] = s->value();
            } else if (const auto* i = dynamic_cast<const Imf::IntAttribute*>(&it.attribute())) {
                out.attributes[it.name()] = i->value();
            } else if (const auto* d = dynamic_cast<const Imf::DoubleAttribute*>(&it.attribute())) {
                out.attributes[it.name()] = d->value();
            } else if (const auto* f = dynamic_cast<const Imf::FloatAttribute*>(&it.attribute())) {
                out.attributes[it.name()] = f->value();
            } else if (const auto* c =
                           dynamic_cast<const Imf::ChromaticitiesAttribute*>(&it.attribute())) {
                const Imf::Chromaticities& v = c->value();
                out.attributes[it.name()] =
                    ExrChromaticities{v.red.x,  v.red.y,  v.green.x, v.green.y,
                                      v.blue.x, v.blue.y, v.white.x, v.white.y};
            }
        }
        return out;
    } catch (const std::exception& e) {
        return absl::InvalidArgumentError(path + ": cannot read EXR: " + e.what());
    }
}

uint8_t EncodeSrgb8(float linear) {
    const float v = std::clamp(std::isfinite(linear) ? linear : 0.0f, 0.0f, 1.0f);
    const float s = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
    return uint8_t(std::lround(s * 255.0f));
}

namespace {

// R,G,B of every pixel, 8-bit sRGB, row by row.
std::vector<uint8_t> Srgb8Pixels(const Image& image, const PngOptions& options) {
    const float scale = float(std::exp2(options.exposure));
    std::vector<uint8_t> rgb(size_t(image.width()) * image.height() * 3);
    for (int y = 0; y < image.height(); ++y) {
        for (int x = 0; x < image.width(); ++x) {
            const Rgb c = image.Pixel(x, y) * scale;
            uint8_t* out = &rgb[(size_t(y) * image.width() + x) * 3];
            for (int k = 0; k < 3; ++k) out[k] = EncodeSrgb8(ApplyToneCurve(options.tone, c[k]));
        }
    }
    return rgb;
}

png_image PngHeader(const Image& image) {
    png_image png{};
    png.version = PNG_IMAGE_VERSION;
    png.width = png_uint_32(image.width());
    png.height = png_uint_32(image.height());
    png.format = PNG_FORMAT_RGB;
    return png;
}

}  // namespace

absl::StatusOr<std::string> EncodePng(const Image& image, const PngOptions& options) {
    const std::vector<uint8_t> rgb = Srgb8Pixels(image, options);
    png_image png = PngHeader(image);
    png_alloc_size_t size = 0;  // asked first, then written
    std::string bytes;
    if (png_image_write_to_memory(&png, nullptr, &size, 0, rgb.data(), 0, nullptr)) {
        bytes.resize(size);
        if (png_image_write_to_memory(&png, bytes.data(), &size, 0, rgb.data(), 0, nullptr)) {
            bytes.resize(size);
            return bytes;
        }
    }
    std::string message = png.message;
    png_image_free(&png);
    return absl::InternalError("cannot encode PNG: " + message);
}

absl::Status WritePng(const std::string& path, const Image& image, const PngOptions& options) {
    const std::vector<uint8_t> rgb = Srgb8Pixels(image, options);
    png_image png = PngHeader(image);
    if (!png_image_write_to_file(&png, path.c_str(), 0, rgb.data(), 0, nullptr)) {
        std::string message = png.message;
        png_image_free(&png);
        return absl::UnavailableError(path + ": cannot write PNG: " + message);
    }
    return absl::OkStatus();
}

}  // namespace lf
