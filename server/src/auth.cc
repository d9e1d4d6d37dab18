#include "lf/server/auth.h"

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"

namespace lf {

namespace {

// Unknown tokens are cached too (a client retrying with a wrong one costs no reads), so the
// cache is bounded: past this many entries it starts over.
constexpr size_t kMaxCachedTokens = 4096;
constexpr size_t kMaxTokenBytes = 256;

bool RoleMay(Role role, Action action) {
    switch (role) {
        case Role::kAdmin:
            return true;
        case Role::kWorker:
            return action == Action::kWork;
        case Role::kSubmitter:
            return action != Action::kWork && action != Action::kManageWorkers;
    }
    return false;
}

}  // namespace

const char* ActionName(Action action) {
    switch (action) {
        case Action::kUploadBlobs:
            return "upload scene files";
        case Action::kSubmit:
            return "submit jobs";
        case Action::kReadJobs:
            return "see jobs";
        case Action::kCancelJob:
            return "cancel jobs";
        case Action::kSetPriority:
            return "change job priorities";
        case Action::kDeleteJob:
            return "delete jobs";
        case Action::kListWorkers:
            return "list workers";
        case Action::kWork:
            return "lease and render tasks";
        case Action::kManageWorkers:
            return "disable, enable or drain workers";
        case Action::kManageJobs:
            return "requeue, pause or resume jobs";
    }
    return "?";
}

absl::Status Permit(const Caller& caller, Action action) {
    if (RoleMay(caller.role, action)) return absl::OkStatus();
    return absl::PermissionDeniedError(absl::StrCat("token \"", caller.name, "\" has role ",
                                                    RoleName(caller.role), ", which may not ",
                                                    ActionName(action)));
}

bool MaySee(const Caller& caller, std::string_view owner) {
    return caller.role == Role::kAdmin || (caller.role == Role::kSubmitter && owner == caller.name);
}

std::unique_ptr<Authenticator> Authenticator::Off() {
    return std::unique_ptr<Authenticator>(new Authenticator());
}

Authenticator::Authenticator(std::unique_ptr<TokenStore> store, bool required)
    : store_(std::move(store)), required_(required) {}

bool Authenticator::enabled() {
    if (required_) return true;
    if (!store_) return false;
    std::lock_guard<std::mutex> lock(mutex_);
    const absl::Time now = absl::Now();
    if (now >= any_until_) {
        // Once on, on for good: tokens are revoked, never removed.
        absl::StatusOr<bool> any = store_->Any();
        // A store that cannot be read must not open the farm: fail closed.
        any_ = !any.ok() || *any;
        any_until_ = any_ ? absl::InfiniteFuture() : now + kCacheFor;
    }
    return any_;
}

absl::StatusOr<std::optional<TokenInfo>> Authenticator::Lookup(const std::string& token) {
    std::lock_guard<std::mutex> lock(mutex_);
    const absl::Time now = absl::Now();
    if (auto it = cache_.find(token); it != cache_.end() && now < it->second.until) {
        return it->second.info;
    }
    absl::StatusOr<std::optional<TokenInfo>> info = store_->Find(token);
    if (!info.ok()) return info.status();
    if (cache_.size() >= kMaxCachedTokens) cache_.clear();
    cache_[token] = Cached{*info, now + kCacheFor};
    return info;
}

absl::StatusOr<Caller> Authenticator::Authenticate(std::optional<std::string_view> header) {
    if (!enabled()) return Caller{};
    constexpr std::string_view kScheme = "Bearer ";
    if (!header) {
        return absl::UnauthenticatedError(
            "this server requires a token: pass --token-file FILE or set LIGHTFARM_TOKEN (an "
            "admin makes one with `lightfarm-server token create`)");
    }
    if (header->size() > kMaxTokenBytes ||
        !absl::StartsWithIgnoreCase(std::string(*header), std::string(kScheme))) {
        return absl::UnauthenticatedError(
            "the authorization metadata is not \"Bearer TOKEN\" with a lightfarm token");
    }
    const std::string token(header->substr(kScheme.size()));
    absl::StatusOr<std::optional<TokenInfo>> info = Lookup(token);
    if (!info.ok()) {
        return absl::UnavailableError(
            absl::StrCat("tokens cannot be checked now: ", info.status().message()));
    }
    if (!*info) {
        return absl::UnauthenticatedError(
            "the token is not one of this server's: check --token-file or LIGHTFARM_TOKEN");
    }
    if (!(*info)->valid()) {
        return absl::UnauthenticatedError(absl::StrCat(
            "token \"", (*info)->name, "\" was revoked on ", absl::FormatTime((*info)->revoked)));
    }
    return Caller{(*info)->name, (*info)->role};
}

}  // namespace lf
