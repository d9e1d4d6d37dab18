#include "lf/server/preview_channels.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "lf/core/aov.h"

namespace lf {

namespace {

struct ViewSource {
    const char* name;
    const char* channels[3];  // the image's channels shown as R, G, B
};

constexpr ViewSource kViews[] = {
    {"beauty", {"R", "G", "B"}},
    {"A", {"A.R", "A.G", "A.B"}},
    {"B", {"B.R", "B.G", "B.B"}},
    {"albedo", {kAovAlbedoChannels[0], kAovAlbedoChannels[1], kAovAlbedoChannels[2]}},
    {"normal", {kAovNormalChannels[0], kAovNormalChannels[1], kAovNormalChannels[2]}},
    {"depth", {kAovDepthChannel, kAovDepthChannel, kAovDepthChannel}},
    {"illuminance", {kAovIlluminanceChannel, kAovIlluminanceChannel, kAovIlluminanceChannel}},
};

bool Has(const Image& image, const ViewSource& view) {
    return std::all_of(std::begin(view.channels), std::end(view.channels),
                       [&](const char* c) { return image.FindChannel(c) != nullptr; });
}

}  // namespace

std::vector<std::string> PreviewChannels(const Image& image) {
    std::vector<std::string> names;
    for (const ViewSource& view : kViews) {
        if (Has(image, view)) names.push_back(view.name);
    }
    return names;
}

absl::StatusOr<ChannelView> ViewChannel(const Image& image, const std::string& channel) {
    const ViewSource* view = nullptr;
    for (const ViewSource& v : kViews) {
        if (v.name == channel && Has(image, v)) view = &v;
    }
    if (!view) {
        return absl::InvalidArgumentError(
            absl::StrCat("channel: the image has no \"", channel, "\"; it has ",
                         absl::StrJoin(PreviewChannels(image), ", ")));
    }
    ChannelView out{.rgb = Image(image.width(), image.height())};
    const std::string name = view->name;
    float scale = 1, offset = 0;
    if (name == "normal") {
        scale = offset = 0.5f;
    } else if (name == "depth" || name == "illuminance") {
        float far = 0;
        for (float z : *image.FindChannel(view->channels[0])) {
            if (std::isfinite(z)) far = std::max(far, z);
        }
        scale = far > 0 ? 1 / far : 1;
    }
    if (name != "beauty" && name != "A" && name != "B") out.tone = ToneCurve::kClamp;
    const char* rgb[3] = {"R", "G", "B"};
    for (int c = 0; c < 3; ++c) {
        const std::vector<float>& from = *image.FindChannel(view->channels[c]);
        std::vector<float>& to = out.rgb.Channel(rgb[c]);
        to.resize(from.size());
        std::transform(from.begin(), from.end(), to.begin(),
                       [&](float v) { return v * scale + offset; });
    }
    return out;
}

}  // namespace lf
