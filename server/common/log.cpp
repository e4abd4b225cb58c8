#include "common/log.h"

#include <spdlog/sinks/stdout_sinks.h>

#include <atomic>
#include <cstdio>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <random>

namespace rdmesh::server {
namespace {

std::atomic<LogFormat> g_format{LogFormat::kText};

}  // namespace

bool InitLogging(LogFormat format, const std::string& level) {
  const spdlog::level::level_enum parsed = spdlog::level::from_str(level);
  if (parsed == spdlog::level::off && level != "off") return false;
  g_format = format;
  auto logger = std::make_shared<spdlog::logger>("rdmeshd",
                                                 std::make_shared<spdlog::sinks::stderr_sink_mt>());
  if (format == LogFormat::kJson) {
    // The message part (%v) is the rest of the JSON object, built by LogLine.
    logger->set_pattern(R"({"time":"%Y-%m-%dT%H:%M:%S.%e%z","level":"%l","thread":%t,%v})");
  } else {
    logger->set_pattern("%Y-%m-%d %H:%M:%S.%e %l [%t] %v");
  }
  logger->set_level(parsed);
  logger->flush_on(spdlog::level::info);
  spdlog::set_default_logger(logger);
  return true;
}

void LogLine(spdlog::level::level_enum level, const std::string& request_id,
             const std::string& message) {
  if (g_format.load() == LogFormat::kJson) {
    const std::string line =
        "\"request_id\":" + nlohmann::json(request_id).dump() + ",\"msg\":" +
        nlohmann::json(message).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    spdlog::log(level, "{}", line);
  } else {
    spdlog::log(level, "req={} {}", request_id, message);
  }
}

std::string NewRequestId() {
  static std::mutex mutex;
  static std::mt19937_64 engine{std::random_device{}()};
  uint64_t value;
  {
    std::lock_guard<std::mutex> lock(mutex);
    value = engine();
  }
  char buffer[17];
  std::snprintf(buffer, sizeof(buffer), "%016llx", static_cast<unsigned long long>(value));
  return buffer;
}

std::string RequestIdFrom(const std::string& client_value) {
  if (client_value.empty() || client_value.size() > 64) return NewRequestId();
  for (char c : client_value) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '.' || c == '_' || c == '-';
    if (!ok) return NewRequestId();
  }
  return client_value;
}

}  // namespace rdmesh::server
