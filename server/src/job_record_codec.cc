#include "lf/server/job_record_codec.h"

#include <google/protobuf/util/json_util.h>

#include "absl/strings/str_cat.h"
#include "lf/wire/stored_job.h"

namespace lf {

namespace {

std::string ToJson(const google::protobuf::Message& stored) {
    google::protobuf::util::JsonPrintOptions options;
    // Every field, also those at their zero value, by the names the store's queries use.
    options.always_print_primitive_fields = true;
    options.preserve_proto_field_names = true;
    std::string text;
    // Printing a message without Any fields cannot fail.
    (void)google::protobuf::util::MessageToJsonString(stored, &text, options);
    return text;
}

}  // namespace

std::string EncodeJobRecord(const JobRecord& record) {
    lightfarm::v1::StoredJob stored;
    ToProto(record, &stored);
    return ToJson(stored);
}

std::string EncodeTaskHistory(const TaskHistory& history) {
    lightfarm::v1::StoredTaskHistory stored;
    ToProto(history, &stored);
    return ToJson(stored);
}

absl::StatusOr<TaskHistory> DecodeTaskHistory(std::string_view text) {
    if (text.empty()) return TaskHistory{};
    lightfarm::v1::StoredTaskHistory stored;
    if (const auto parsed = google::protobuf::util::JsonStringToMessage(text, &stored);
        !parsed.ok()) {
        return absl::DataLossError(
            absl::StrCat("the stored task history is unreadable: ", parsed.message().as_string()));
    }
    return FromProto(stored);
}

absl::StatusOr<JobRecord> DecodeJobRecord(std::string_view text) {
    lightfarm::v1::StoredJob stored;
    if (const auto parsed = google::protobuf::util::JsonStringToMessage(text, &stored);
        !parsed.ok()) {
        return absl::DataLossError(
            absl::StrCat("the stored record is unreadable: ", parsed.message().as_string()));
    }
    absl::StatusOr<JobRecord> record = FromProto(stored);
    if (!record.ok()) {
        return absl::DataLossError(
            absl::StrCat("the stored record's state: ", record.status().message()));
    }
    return record;
}

}  // namespace lf
