#include "scene_json.h"

#include <algorithm>
#include <cstddef>
#include <string>

#include "absl/strings/str_cat.h"

namespace lf::scene_internal {
namespace {

// nlohmann reports a number too large for a double without its position; as a SAX parser this
// sees the byte offset of every error, so each one can name a line and column.
class LocatingDomParser : public nlohmann::detail::json_sax_dom_parser<Json> {
  public:
    explicit LocatingDomParser(Json& result) : json_sax_dom_parser(result, false) {}

    bool parse_error(std::size_t byte, const std::string&, const nlohmann::detail::exception& e) {
        error_byte = byte;
        error = e.what();
        return false;
    }

    std::size_t error_byte = 0;
    std::string error;
};

}  // namespace

absl::Status ParseJson(const std::string& text, const std::string& source, Json& root) {
    LocatingDomParser parser(root);
    if (Json::sax_parse(text, &parser)) return absl::OkStatus();
    // The offset counts the characters read, so the offending one is just before it.
    const size_t at = std::min(text.size(), parser.error_byte > 0 ? parser.error_byte - 1 : 0);
    const size_t line = 1 + std::count(text.begin(), text.begin() + at, '\n');
    const size_t newline = at == 0 ? std::string::npos : text.rfind('\n', at - 1);
    const size_t column = at + 1 - (newline == std::string::npos ? 0 : newline + 1);
    // Drop nlohmann's "[json.exception.parse_error.101] parse error at line 2, column 9: ".
    std::string message = parser.error.substr(parser.error.find(']') + 2);
    if (message.starts_with("parse error")) message = message.substr(message.find(": ") + 2);
    return absl::InvalidArgumentError(
        absl::StrCat(source, ":", line, ":", column, ": JSON syntax error: ", message));
}

std::string Describe(const Json& json) {
    if (json.is_string()) return absl::StrCat("string \"", json.get<std::string>(), "\"");
    if (json.is_number()) return absl::StrCat("number ", json.get<double>());
    return json.type_name();
}

}  // namespace lf::scene_internal
