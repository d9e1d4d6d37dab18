// Where the server may listen, and how: beyond loopback, only with TLS (or when told to take
// the risk with --insecure), and with authentication on.
#pragma once

#include <string>
#include <string_view>

#include "absl/status/status.h"

namespace lf {

// The host part of HOST:PORT ("[::1]:7070" gives "::1").
std::string_view ListenHost(std::string_view listen);
// True for addresses only this machine reaches: 127.0.0.0/8, ::1, localhost. Not 0.0.0.0 or
// [::], which listen on every interface.
bool IsLoopbackHost(std::string_view host);

// FailedPrecondition, saying what to do, for a non-loopback `listen` without TLS and without
// `insecure`.
absl::Status CheckListenPolicy(std::string_view listen, bool tls, bool insecure);

}  // namespace lf
