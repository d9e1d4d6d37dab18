// Who may do what on the farm: the caller a bearer token names, the actions each role may take,
// and which jobs a caller sees. Plain logic; the gRPC services ask it first thing in every call
// (server/grpc_service.cc) and map its statuses to UNAUTHENTICATED and PERMISSION_DENIED.
//
// Authentication is on once the data folder's token store holds a token (a revoked one
// counts), or whenever the server listens beyond loopback; off, every caller acts as an
// anonymous admin, as a farm on one machine did before tokens.
#pragma once

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "lf/server/token_store.h"

namespace lf {

enum class Action {
    kUploadBlobs,  // MissingBlobs, UploadBlob
    kSubmit,
    kReadJobs,       // GetJob, ListJobs, WatchJob, FetchResult: own jobs, or all for an admin
    kCancelJob,      // own jobs, or all for an admin
    kSetPriority,    // own jobs, or all for an admin
    kDeleteJob,      // own jobs, or all for an admin
    kListWorkers,    // the farm's workers: admins and submitters
    kWork,           // LeaseTask, Heartbeat, CompleteTask, FailTask, FetchBlob
    kManageWorkers,  // SetWorkerState: admins only
    // Job management (issue 30): RequeueJob, PauseJob, ResumeJob; own jobs, or all for an admin.
    kManageJobs,
};
const char* ActionName(Action action);

struct Caller {
    std::string name;  // the token's name; "" with authentication off
    Role role = Role::kAdmin;
};

// Ok when `role` may take `action`; PermissionDenied naming the caller, its role and the action
// otherwise.
absl::Status Permit(const Caller& caller, Action action);
// Whether `caller` may see, watch, fetch, cancel or delete a job of `owner`: admins every job,
// submitters their own.
bool MaySee(const Caller& caller, std::string_view owner);

class Authenticator {
  public:
    // Authentication off: every caller is an anonymous admin. For tests and for tools.
    static std::unique_ptr<Authenticator> Off();
    // Tokens from `store`; `required`: on even while the store holds none (a server beyond
    // loopback), so that no call gets through before the first token is made.
    Authenticator(std::unique_ptr<TokenStore> store, bool required);

    // The caller of a call whose `authorization` metadata is `header` (nullopt when absent).
    // Unauthenticated, saying what is wrong and what to do, for a missing, malformed, unknown or
    // revoked token while authentication is on.
    absl::StatusOr<Caller> Authenticate(std::optional<std::string_view> header);
    // Whether calls need a token now.
    bool enabled();

  private:
    Authenticator() = default;
    // Lookups are cached for a second: a call costs a hash lookup, not a read of tokens.db, and
    // a revocation still takes effect within a second.
    static constexpr absl::Duration kCacheFor = absl::Seconds(1);
    struct Cached {
        std::optional<TokenInfo> info;
        absl::Time until;
    };
    absl::StatusOr<std::optional<TokenInfo>> Lookup(const std::string& token);

    std::unique_ptr<TokenStore> store_;
    bool required_ = false;
    std::mutex mutex_;  // the store's connection and the caches
    std::unordered_map<std::string, Cached> cache_;
    bool any_ = false;
    absl::Time any_until_ = absl::InfinitePast();
};

}  // namespace lf
