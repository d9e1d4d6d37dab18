#include "lf/server/retention_flag.h"

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"

namespace lf {

absl::StatusOr<absl::Duration> ParseRetention(const std::string& text) {
    const auto bad = [&] {
        return absl::InvalidArgumentError(
            absl::StrCat("retention \"", text,
                         "\": expected a duration such as 7d, 1d12h, 12h or 30m, or 0 "
                         "to keep ended jobs forever"));
    };
    if (text == "0") return absl::ZeroDuration();
    absl::Duration days = absl::ZeroDuration();
    absl::string_view rest = text;
    // absl::ParseDuration has no days; none of its units has a `d` in it.
    if (const size_t d = rest.find('d'); d != absl::string_view::npos) {
        double count = 0;
        if (!absl::SimpleAtod(rest.substr(0, d), &count) || !(count >= 0)) return bad();
        days = absl::Hours(24) * count;
        rest = rest.substr(d + 1);
    }
    absl::Duration more = absl::ZeroDuration();
    if (!rest.empty() && !absl::ParseDuration(rest, &more)) return bad();
    if (more < absl::ZeroDuration() || more == absl::InfiniteDuration() || text.empty()) {
        return bad();
    }
    return days + more;
}

}  // namespace lf
