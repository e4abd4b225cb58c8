#include "mesh_job.h"

#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

#include "convert.h"

namespace rdmesh::server {
namespace {

namespace pb = ::rdmesh::v1;
using Clock = std::chrono::steady_clock;
constexpr std::chrono::milliseconds kPoll(20);
constexpr std::chrono::milliseconds kProgressInterval(100);

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// Events from the engine's threads to the writing thread. Push waits while the queue is over
/// its byte limit, unless the run is stopping.
class EventQueue {
 public:
  enum class Next { kEvent, kTimeout, kDone };

  EventQueue(std::size_t max_bytes, const Context* context)
      : max_bytes_(max_bytes), context_(context) {}

  void Push(pb::MeshEvent event) {
    const std::size_t size = event.ByteSizeLong();
    std::unique_lock<std::mutex> lock(mutex_);
    while (bytes_ > max_bytes_ && !context_->ShouldStop()) not_full_.wait_for(lock, kPoll);
    bytes_ += size;
    events_.emplace_back(std::move(event), size);
    not_empty_.notify_one();
  }

  void Finish() {
    std::lock_guard<std::mutex> lock(mutex_);
    finished_ = true;
    not_empty_.notify_one();
  }

  Next Pop(pb::MeshEvent* out, std::chrono::milliseconds wait) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (events_.empty() && !finished_) not_empty_.wait_for(lock, wait);
    if (events_.empty()) return finished_ ? Next::kDone : Next::kTimeout;
    *out = std::move(events_.front().first);
    bytes_ -= events_.front().second;
    events_.pop_front();
    not_full_.notify_all();
    return Next::kEvent;
  }

 private:
  const std::size_t max_bytes_;
  const Context* context_;
  std::mutex mutex_;
  std::condition_variable not_empty_;
  std::condition_variable not_full_;
  std::deque<std::pair<pb::MeshEvent, std::size_t>> events_;
  std::size_t bytes_ = 0;
  bool finished_ = false;
};

}  // namespace

MeshJob::MeshJob(Params params, const RequestLog* log, std::atomic<int>* active_jobs)
    : params_(std::move(params)), log_(log), active_jobs_(active_jobs) {}

Status MeshJob::Run(const WriteFn& write, const CancelledFn& cancelled) {
  const Model& model = *params_.model->model;
  const int face_total = params_.model->info.faces;
  Context context;
  // The earlier of the call's deadline and the request's timeout_seconds.
  std::optional<Clock::time_point> deadline;
  if (params_.deadline != std::chrono::system_clock::time_point::max()) {
    deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                  params_.deadline - std::chrono::system_clock::now());
  }
  if (params_.options.timeout_seconds > 0) {
    const auto timeout =
        Clock::now() + std::chrono::duration_cast<Clock::duration>(
                           std::chrono::duration<double>(params_.options.timeout_seconds));
    if (!deadline || timeout < *deadline) deadline = timeout;
  }
  if (deadline) context.SetDeadline(*deadline);

  std::vector<bool> requested(face_total + 1, params_.options.face_ids.empty());
  for (int id : params_.options.face_ids) {
    if (id >= 1 && id <= face_total) requested[id] = true;
  }

  EventQueue queue(params_.max_queued_bytes, &context);
  std::mutex state_mutex;  // guards the callback state below
  std::vector<bool> streamed(face_total + 1, false);
  int64_t triangles_streamed = 0;
  bool over_limit = false;
  std::optional<Progress::Stage> last_stage;
  Clock::time_point last_progress;

  // A triangle budget makes the engine run several trial meshes through the same callbacks;
  // only the final result counts then.
  const bool stream_faces = params_.options.max_triangles == 0;
  context.set_face_callback([&](const FaceMesh& face) {
    if (!stream_faces) return;
    {
      std::lock_guard<std::mutex> lock(state_mutex);
      if (face.face_id < 1 || face.face_id > face_total || !requested[face.face_id] || over_limit) {
        return;
      }
      triangles_streamed += face.triangle_count();
      if (params_.max_triangles > 0 && triangles_streamed > params_.max_triangles) {
        over_limit = true;
        context.Cancel();
        return;
      }
      streamed[face.face_id] = true;
    }
    for (pb::FaceMesh& part : SplitFaceMesh(face, params_.with_uv, params_.with_normals,
                                            kMaxFaceMessageBytes, params_.with_deviation)) {
      pb::MeshEvent event;
      *event.mutable_face() = std::move(part);
      queue.Push(std::move(event));
    }
  });
  context.set_progress_callback([&](const Progress& progress) {
    {
      std::lock_guard<std::mutex> lock(state_mutex);
      const Clock::time_point now = Clock::now();
      const bool due = !last_stage || *last_stage != progress.stage ||
                       progress.done == progress.total || now - last_progress >= kProgressInterval;
      if (!due) return;
      last_stage = progress.stage;
      last_progress = now;
    }
    pb::MeshEvent event;
    pb::Progress* out = event.mutable_progress();
    out->set_stage(ToProto(progress.stage));
    out->set_done(progress.done);
    out->set_total(progress.total);
    queue.Push(std::move(event));
  });

  std::optional<Result<MeshResult>> result;
  active_jobs_->fetch_add(1);
  std::thread worker([&] {
    try {
      result.emplace(MeshModel(model, params_.options, &context));
    } catch (const std::exception& e) {
      result.emplace(Status(StatusCode::kInternal, std::string("engine exception: ") + e.what()));
    } catch (...) {
      result.emplace(Status(StatusCode::kInternal, "unknown engine exception"));
    }
    active_jobs_->fetch_sub(1);
    queue.Finish();
  });

  // Drain on this thread: the only writer of the stream.
  bool client_gone = false;
  bool write_failed = false;
  pb::MeshEvent event;
  while (true) {
    const EventQueue::Next next = queue.Pop(&event, kPoll);
    if (next == EventQueue::Next::kDone) break;
    if (!client_gone && cancelled()) {
      client_gone = true;
      context.Cancel();
      log_->Info("client cancelled; stopping the engine");
    }
    if (next == EventQueue::Next::kTimeout || client_gone || write_failed) continue;
    if (event.has_face()) ++face_messages_;
    if (!write(event)) {
      write_failed = true;
      context.Cancel();
      log_->Warn("write to the client failed; stopping the engine");
    }
  }
  worker.join();

  if (over_limit) {
    return Status(StatusCode::kResourceExhausted,
                  "the mesh passes the server's --max-triangles limit of " +
                      std::to_string(params_.max_triangles) +
                      " triangles; ask for a coarser mesh or a max_triangles budget");
  }
  if (!result->ok()) return result->status();
  if (client_gone || write_failed) return Status(StatusCode::kCancelled, "client went away");
  if (params_.max_triangles > 0 && result->value().summary.triangles > params_.max_triangles) {
    return Status(StatusCode::kResourceExhausted,
                  "the mesh has " + std::to_string(result->value().summary.triangles) +
                      " triangles, more than the server's --max-triangles limit of " +
                      std::to_string(params_.max_triangles));
  }

  // Faces the per-face callback did not report (budget runs, or faces the engine did not report)
  // follow now, then every welded face's global ids.
  const MeshResult& mesh = result->value();
  for (const FaceMesh& face : mesh.faces) {
    if (face.face_id < 1 || face.face_id > face_total || !requested[face.face_id] ||
        streamed[face.face_id]) {
      continue;
    }
    for (pb::FaceMesh& part : SplitFaceMesh(face, params_.with_uv, params_.with_normals,
                                            kMaxFaceMessageBytes, params_.with_deviation)) {
      pb::MeshEvent out;
      *out.mutable_face() = std::move(part);
      ++face_messages_;
      if (!write(out)) return Status(StatusCode::kCancelled, "client went away");
    }
  }
  for (const FaceMesh& face : mesh.faces) {
    if (face.status != FaceStatus::kOk || face.face_id < 1 || face.face_id > face_total ||
        !requested[face.face_id]) {
      continue;
    }
    for (pb::FaceNodeIds& part :
         SplitFaceNodeIds(face, params_.with_topology ? &mesh.mesh : nullptr)) {
      pb::MeshEvent out;
      *out.mutable_node_ids() = std::move(part);
      if (!write(out)) return Status(StatusCode::kCancelled, "client went away");
    }
  }
  if (params_.with_edges) {
    for (const EdgeLine& line : mesh.edges) {
      for (pb::EdgePolyline& part : SplitEdgeLine(line)) {
        pb::MeshEvent out;
        *out.mutable_edge() = std::move(part);
        if (!write(out)) return Status(StatusCode::kCancelled, "client went away");
      }
    }
  }
  summary_ = mesh.summary;
  pb::MeshEvent out;
  pb::Summary* summary = out.mutable_summary();
  *summary = ToProto(mesh.summary);
  summary->set_total_seconds(SecondsSince(params_.start));
  summary->set_face_messages(face_messages_);
  if (!write(out)) return Status(StatusCode::kCancelled, "client went away");
  return Status::Ok();
}

}  // namespace rdmesh::server
