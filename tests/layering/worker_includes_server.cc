// A worker-side file that includes the coordinator: the build must refuse it (lf_worker does not
// link lf_server, so the header is not on its include path). Built only by the
// layering_build_refuses_worker_including_server test, never by `all`.
#include "lf/server/scheduler.h"
