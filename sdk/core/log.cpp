#include "core/log.h"

#include <atomic>
#include <cstdio>

namespace blvd::core {
namespace {
void stderrSink(LogLevel level, const char* message, void*) {
  static const char* names[] = {"debug", "info", "warn", "error"};
  std::fprintf(stderr, "blvd %s: %s\n", names[static_cast<int>(level)], message);
}
std::atomic<LogSink> g_sink{stderrSink};
std::atomic<void*> g_user{nullptr};
std::atomic<int> g_min{static_cast<int>(LogLevel::Info)};
}  // namespace

void setLogSink(LogSink sink, void* user) {
  g_user = user;
  g_sink = sink ? sink : stderrSink;
}

void setLogLevel(LogLevel min_level) { g_min = static_cast<int>(min_level); }

void logf(LogLevel level, const char* fmt, ...) {
  if (static_cast<int>(level) < g_min) return;
  char buf[1024];  // fixed: logging never allocates
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  g_sink.load()(level, buf, g_user.load());
}

}  // namespace blvd::core
