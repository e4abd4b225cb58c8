#pragma once
// Logging: spdlog to stderr, as text or as one JSON object per line. Every line carries a request
// id ("-" for lines that belong to no request).

#include <spdlog/spdlog.h>

#include <string>
#include <utility>

namespace rdmesh::server {

enum class LogFormat { kText, kJson };

/// Sets up the default logger. `level` is an spdlog level name: trace, debug, info, warn, error,
/// critical or off. Returns false (and logs nothing) for an unknown level. Call once, before any
/// other thread logs.
bool InitLogging(LogFormat format, const std::string& level);

/// Writes one line for `request_id`. Thread-safe.
void LogLine(spdlog::level::level_enum level, const std::string& request_id,
             const std::string& message);

/// A request-scoped logger: every line it writes carries the request id.
class RequestLog {
 public:
  explicit RequestLog(std::string request_id) : id_(std::move(request_id)) {}

  const std::string& id() const { return id_; }

  template <typename... Args>
  void Info(fmt::format_string<Args...> format, Args&&... args) const {
    Write(spdlog::level::info, format, std::forward<Args>(args)...);
  }
  template <typename... Args>
  void Warn(fmt::format_string<Args...> format, Args&&... args) const {
    Write(spdlog::level::warn, format, std::forward<Args>(args)...);
  }
  template <typename... Args>
  void Debug(fmt::format_string<Args...> format, Args&&... args) const {
    Write(spdlog::level::debug, format, std::forward<Args>(args)...);
  }
  template <typename... Args>
  void Error(fmt::format_string<Args...> format, Args&&... args) const {
    Write(spdlog::level::err, format, std::forward<Args>(args)...);
  }

 private:
  template <typename... Args>
  void Write(spdlog::level::level_enum level, fmt::format_string<Args...> format,
             Args&&... args) const {
    if (!spdlog::should_log(level)) return;
    LogLine(level, id_, fmt::format(format, std::forward<Args>(args)...));
  }

  std::string id_;
};

/// A new request id: 16 hex digits, random.
std::string NewRequestId();

/// The id a client sent in its "x-request-id" metadata when it is 1-64 characters of
/// [A-Za-z0-9._-]; otherwise a new one.
std::string RequestIdFrom(const std::string& client_value);

}  // namespace rdmesh::server
