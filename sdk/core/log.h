// Minimal leveled logger. The sink is replaceable (setLogSink: the CLI and
// tests use it; the C API has no logger hook yet); the default writes to stderr.
#pragma once
#include <cstdarg>

namespace blvd::core {

enum class LogLevel : int { Debug = 0, Info = 1, Warn = 2, Error = 3 };

using LogSink = void (*)(LogLevel level, const char* message, void* user);

void setLogSink(LogSink sink, void* user);
void setLogLevel(LogLevel min_level);
void logf(LogLevel level, const char* fmt, ...) __attribute__((format(printf, 2, 3)));

}  // namespace blvd::core

#define BLVD_LOG_DEBUG(...) ::blvd::core::logf(::blvd::core::LogLevel::Debug, __VA_ARGS__)
#define BLVD_LOG_INFO(...) ::blvd::core::logf(::blvd::core::LogLevel::Info, __VA_ARGS__)
#define BLVD_LOG_WARN(...) ::blvd::core::logf(::blvd::core::LogLevel::Warn, __VA_ARGS__)
#define BLVD_LOG_ERROR(...) ::blvd::core::logf(::blvd::core::LogLevel::Error, __VA_ARGS__)
