#include "lf/server/stream_slots.h"

#include "absl/strings/str_cat.h"

namespace lf {

StreamSlots::Slot::~Slot() {
    if (slots_) slots_->Release(token_);
}

absl::StatusOr<StreamSlots::Slot> StreamSlots::Take(const std::string& token) {
    std::lock_guard<std::mutex> lock(mutex_);
    const std::string hint = limits_.hint.empty() ? "" : ", " + limits_.hint;
    if (limits_.max > 0 && open_ >= limits_.max) {
        return absl::ResourceExhaustedError(
            absl::StrCat("this server already serves its most ", limits_.what, ", ", limits_.max,
                         " (lightfarm-server ", limits_.max_flag, "): try again later", hint));
    }
    if (!token.empty() && limits_.max_per_token > 0) {
        auto it = per_token_.find(token);
        if (it != per_token_.end() && it->second >= limits_.max_per_token) {
            return absl::ResourceExhaustedError(
                absl::StrCat("token \"", token, "\" already holds ", it->second, " ", limits_.what,
                             ", the most one token may (lightfarm-server ", limits_.per_token_flag,
                             "): end one or try again later", hint));
        }
        ++per_token_[token];
    }
    ++open_;
    return Slot(this, token);
}

void StreamSlots::Release(const std::string& token) {
    std::lock_guard<std::mutex> lock(mutex_);
    --open_;
    if (token.empty() || limits_.max_per_token <= 0) return;
    if (auto it = per_token_.find(token); it != per_token_.end() && --it->second == 0) {
        per_token_.erase(it);
    }
}

}  // namespace lf
