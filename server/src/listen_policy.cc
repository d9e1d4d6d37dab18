#include "lf/server/listen_policy.h"

#include <string>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"

namespace lf {

std::string_view ListenHost(std::string_view listen) {
    // gRPC's own URI schemes name loopback interfaces too, but a bare HOST:PORT is what the
    // server documents.
    const size_t colon = listen.rfind(':');
    std::string_view host = colon == std::string_view::npos ? listen : listen.substr(0, colon);
    if (host.size() >= 2 && host.front() == '[' && host.back() == ']') {
        host = host.substr(1, host.size() - 2);
    }
    return host;
}

bool IsLoopbackHost(std::string_view host_view) {
    const std::string host = absl::AsciiStrToLower(std::string(host_view));
    if (host == "localhost" || host == "::1" || host == "::ffff:127.0.0.1") return true;
    // 127.0.0.0/8, as four decimal parts.
    const std::vector<std::string> parts = absl::StrSplit(host, '.');
    if (parts.size() != 4) return false;
    for (const std::string& part : parts) {
        int value = 0;
        if (part.empty() || part.size() > 3 || !absl::SimpleAtoi(part, &value) || value < 0 ||
            value > 255) {
            return false;
        }
    }
    return parts[0] == "127";
}

absl::Status CheckListenPolicy(std::string_view listen, bool tls, bool insecure) {
    if (tls || insecure || IsLoopbackHost(ListenHost(listen))) return absl::OkStatus();
    return absl::FailedPreconditionError(absl::StrCat(
        "refusing to listen on ", std::string(listen),
        " without TLS: other machines could read the traffic and its tokens. Give --tls-cert "
        "and --tls-key, listen on 127.0.0.1, or pass --insecure on a network you trust"));
}

}  // namespace lf
