#include "lf/job/worker_tags.h"

#include <algorithm>
#include <set>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"

namespace lf {

namespace {

bool IsTagChar(char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
}

}  // namespace

absl::Status CheckTags(const std::vector<std::string>& tags, const std::string& what) {
    if (tags.size() > kMaxTags) {
        return absl::InvalidArgumentError(
            absl::StrCat(what, ": ", tags.size(), " tags, at most ", kMaxTags));
    }
    std::set<std::string> seen;
    for (const std::string& tag : tags) {
        if (tag.empty() || tag.size() > kMaxTagBytes ||
            !std::all_of(tag.begin(), tag.end(), IsTagChar)) {
            // The tag is the client's: quoted only once it is known to be short.
            return absl::InvalidArgumentError(absl::StrCat(
                what, ": tag \"",
                tag.size() > kMaxTagBytes ? tag.substr(0, kMaxTagBytes) + "..." : tag,
                "\": expected 1 to ", kMaxTagBytes, " characters of a-z, 0-9, _ and -"));
        }
        if (!seen.insert(tag).second) {
            return absl::InvalidArgumentError(absl::StrCat(what, ": tag \"", tag, "\" repeated"));
        }
    }
    return absl::OkStatus();
}

absl::StatusOr<std::vector<std::string>> ParseTags(const std::string& list,
                                                   const std::string& what) {
    std::vector<std::string> tags;
    if (!list.empty()) tags = absl::StrSplit(list, ',');
    if (absl::Status s = CheckTags(tags, what); !s.ok()) return s;
    return tags;
}

bool HasAllTags(const std::vector<std::string>& have, const std::vector<std::string>& need) {
    return std::all_of(need.begin(), need.end(), [&](const std::string& tag) {
        return std::find(have.begin(), have.end(), tag) != have.end();
    });
}

std::string WaitingForTags(const std::vector<std::string>& need) {
    return absl::StrCat("waiting for a worker with tags ", absl::StrJoin(need, ","));
}

}  // namespace lf
