// The edge between the wire (lightfarm.v1 protobuf messages) and the job model: every
// conversion of the server, the workers and the client is here, so neither side sees the
// other's types. Unset fields of older peers keep the job model's defaults.
#pragma once

#include "lf/job/farm_stats.h"
#include "lf/job/job_record.h"
#include "lf/job/job_spec.h"
#include "lf/job/render_metadata.h"
#include "lf/job/task_assignment.h"
#include "lf/job/task_status.h"
#include "lf/job/worker_status.h"
#include "lightfarm/v1/job_service.pb.h"
#include "lightfarm/v1/worker_service.pb.h"

namespace lf {

void ToProto(const BlobRef& ref, lightfarm::v1::SceneFile* out);
BlobRef FromProto(const lightfarm::v1::SceneFile& file);

void ToProto(const RadiositySettings& settings, lightfarm::v1::RadiosityParams* out);
RadiositySettings FromProto(const lightfarm::v1::RadiosityParams& params);

void ToProto(const PhotonSettings& settings, lightfarm::v1::PhotonParams* out);

// The render settings of a spec (not its scene, name or priority).
void ToProto(const JobSpec& spec, lightfarm::v1::RenderParams* out);
// Fills the render settings of `spec` from `params`.
void FromProto(const lightfarm::v1::RenderParams& params, JobSpec* spec);

void ToProto(const JobSpec& spec, lightfarm::v1::SubmitJobRequest* out);
JobSpec FromProto(const lightfarm::v1::SubmitJobRequest& request);

lightfarm::v1::Job::State ToProto(JobState state);
// STATE_UNSPECIFIED, and a state of a newer server, are kQueued, the model's default: not final.
JobState FromProto(lightfarm::v1::Job::State state);
void ToProto(const JobRecord& job, lightfarm::v1::Job* out);

void ToProto(const TaskAssignment& task, lightfarm::v1::Task* out);
TaskAssignment FromProto(const lightfarm::v1::Task& task);

lightfarm::v1::WorkerInfo::State ToProto(WorkerState state);
void ToProto(const WorkerStatus& worker, lightfarm::v1::WorkerInfo* out);

void ToProto(const TaskStatus& task, lightfarm::v1::TaskInfo* out);
void ToProto(const FarmStats& stats, lightfarm::v1::GetStatsResponse* out);
void ToProto(const TaskLogLine& line, lightfarm::v1::TaskLogLine* out);
// A line as the worker captured it: its time, level and text; the server knows the rest.
void ToProto(const TaskLogLine& line, lightfarm::v1::WorkerLogLine* out);
TaskLogLine FromProto(const lightfarm::v1::WorkerLogLine& line);

void ToProto(const RadiosityFigures& figures, lightfarm::v1::RadiosityReport* out);
RadiosityFigures FromProto(const lightfarm::v1::RadiosityReport& report);

}  // namespace lf
