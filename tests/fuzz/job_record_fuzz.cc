// A stored job record, as a coordinator reads its store at start: the StoredJob form
// (DecodeJobRecord, through the wire's FromProto) and the legacy JSON form. Whatever decodes
// must encode again.
#include <string_view>

#include "fuzz_input.h"
#include "lf/server/job_record_codec.h"
#include "lf/server/legacy_job_record.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    lf::fuzz::Quiet();
    const std::string_view stored(reinterpret_cast<const char*>(data), size);
    if (absl::StatusOr<lf::JobRecord> record = lf::DecodeJobRecord(stored); record.ok()) {
        (void)lf::EncodeJobRecord(*record);
    }
    if (absl::StatusOr<lf::JobRecord> legacy = lf::DecodeLegacyJobRecord(stored); legacy.ok()) {
        (void)lf::EncodeJobRecord(*legacy);
    }
    return 0;
}
