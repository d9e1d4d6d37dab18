// The radiosity settings of a job, between their plain form and the wire, for every side of it.
#pragma once

#include "lightfarm/v1/common.pb.h"
#include "server/plan.h"

namespace lf {

void ToProto(const RadiositySettings& settings, lightfarm::v1::RadiosityParams* out);
// Unset fields (an older client) keep the defaults of RadiositySettings.
RadiositySettings FromProto(const lightfarm::v1::RadiosityParams& params);

}  // namespace lf
