// An HTTP request and its answer in plain types: the handlers of server/http_listener.h and
// server/dashboard.h take and return these, so that tests call them without a socket and httplib
// stays inside http_listener.cc.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace lf {

struct HttpRequest {
    std::string method = "GET";
    std::string path;                            // without the query
    std::map<std::string, std::string> query;    // decoded; the first of repeated names
    std::map<std::string, std::string> headers;  // names in lower case
    std::string body;
    std::string remote_addr;  // the peer's IP address

    std::optional<std::string> Header(const std::string& lower_case_name) const {
        auto it = headers.find(lower_case_name);
        return it == headers.end() ? std::nullopt : std::optional<std::string>(it->second);
    }
    std::optional<std::string> Query(const std::string& name) const {
        auto it = query.find(name);
        return it == query.end() ? std::nullopt : std::optional<std::string>(it->second);
    }
};

struct HttpAnswer {
    int status = 200;
    std::string content_type;
    std::string body;
    std::vector<std::pair<std::string, std::string>> headers;  // beyond Content-Type
    // When set, the body is this file, streamed in pieces as the peer reads (`body` unused): a
    // result may be larger than an answer should hold in memory.
    std::string file;
};

}  // namespace lf
