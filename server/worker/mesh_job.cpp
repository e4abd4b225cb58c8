#include "worker/mesh_job.h"

#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

#include "rdmesh/engine.h"
#include "wire/convert.h"

namespace rdmesh::server {
namespace {

namespace pb = ::rdmesh::v1;
using Clock = std::chrono::steady_clock;
constexpr std::chrono::milliseconds kPoll(20);
constexpr std::chrono::milliseconds kProgressInterval(100);

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
  // The level of detail being meshed (0 without levels), and its FaceMesh events so far; set by
  // the engine thread between levels, when no face callback runs.
  std::atomic<int> level{0};
  std::atomic<int64_t> level_face_messages{0};
  std::atomic<int64_t> face_messages{0};

  const auto push_faces = [&](const FaceMesh& face) {
    for (pb::FaceMesh& part : SplitFaceMesh(face, params_.with_uv, params_.with_normals,
                                            kMaxFaceMessageBytes, params_.with_deviation)) {
      part.set_level(level);
      pb::MeshEvent event;
      *event.mutable_face() = std::move(part);
      ++level_face_messages;
      ++face_messages;
      queue.Push(std::move(event));
    }
  };

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
    push_faces(face);
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
    out->set_level(level);
    queue.Push(std::move(event));
  });

  // On the engine thread, once a level (or the one mesh) is done: the faces the per-face callback
  // did not stream (budget runs, or faces the engine did not report), then every welded face's
  // global ids, the edges and the Summary, queued behind its faces.
  const auto finish_level = [&](int done_level, MeshResult mesh) -> Status {
    if (params_.max_triangles > 0 && mesh.summary.triangles > params_.max_triangles) {
      return Status(StatusCode::kResourceExhausted,
                    "the mesh has " + std::to_string(mesh.summary.triangles) +
                        " triangles, more than the server's --max-triangles limit of " +
                        std::to_string(params_.max_triangles));
    }
    for (const FaceMesh& face : mesh.faces) {
      if (context.ShouldStop()) return context.StopStatus();
      if (face.face_id < 1 || face.face_id > face_total || !requested[face.face_id] ||
          streamed[face.face_id]) {
        continue;
      }
      push_faces(face);
    }
    for (const FaceMesh& face : mesh.faces) {
      if (face.status != FaceStatus::kOk || face.face_id < 1 || face.face_id > face_total ||
          !requested[face.face_id]) {
        continue;
      }
      for (pb::FaceNodeIds& part :
           SplitFaceNodeIds(face, params_.with_topology ? &mesh.mesh : nullptr)) {
        part.set_level(done_level);
        pb::MeshEvent out;
        *out.mutable_node_ids() = std::move(part);
        queue.Push(std::move(out));
      }
    }
    if (params_.with_edges) {
      for (const EdgeLine& line : mesh.edges) {
        for (pb::EdgePolyline& part : SplitEdgeLine(line)) {
          part.set_level(done_level);
          pb::MeshEvent out;
          *out.mutable_edge() = std::move(part);
          queue.Push(std::move(out));
        }
      }
    }
    summary_ = mesh.summary;
    pb::MeshEvent out;
    pb::Summary* summary = out.mutable_summary();
    *summary = ToProto(mesh.summary);
    summary->set_level(done_level);
    summary->set_total_seconds(SecondsSince(params_.start));
    summary->set_face_messages(level_face_messages);
    queue.Push(std::move(out));
    return Status::Ok();
  };
  // Before each level of detail: its LevelStarted event, and fresh per-level state.
  const auto start_level = [&](int next) {
    {
      std::lock_guard<std::mutex> lock(state_mutex);
      std::fill(streamed.begin(), streamed.end(), false);
      triangles_streamed = 0;
      last_stage.reset();
    }
    level = next;
    level_face_messages = 0;
    const double rel = params_.levels[next];
    pb::MeshEvent event;
    pb::LevelStarted* started = event.mutable_level_started();
    started->set_level(next);
    started->set_levels(static_cast<int32_t>(params_.levels.size()));
    started->set_max_deviation_rel(rel);
    started->set_max_deviation_abs(rel * params_.model->info.diagonal);
    queue.Push(std::move(event));
  };

  Status run = Status::Ok();
  active_jobs_->fetch_add(1);
  std::thread worker([&] {
    try {
      if (params_.levels.empty()) {
        Result<MeshResult> result = MeshModel(model, params_.options, &context);
        run = result.ok() ? finish_level(0, std::move(*result)) : result.status();
      } else {
        LevelCallbacks callbacks;
        callbacks.started = start_level;
        callbacks.done = finish_level;
        run = MeshModelLevels(model, params_.options, params_.levels, &context, callbacks);
      }
    } catch (const std::exception& e) {
      run = Status(StatusCode::kInternal, std::string("engine exception: ") + e.what());
    } catch (...) {
      run = Status(StatusCode::kInternal, "unknown engine exception");
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
    if (!write(event)) {
      write_failed = true;
      context.Cancel();
      log_->Warn("write to the client failed; stopping the engine");
    }
  }
  worker.join();
  face_messages_ = face_messages;

  if (over_limit) {
    return Status(StatusCode::kResourceExhausted,
                  "the mesh passes the server's --max-triangles limit of " +
                      std::to_string(params_.max_triangles) +
                      " triangles; ask for a coarser mesh or a max_triangles budget");
  }
  if (!run.ok()) return run;
  if (client_gone || write_failed) return Status(StatusCode::kCancelled, "client went away");
  return Status::Ok();
}

}  // namespace rdmesh::server
