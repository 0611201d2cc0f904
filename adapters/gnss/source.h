// Byte sources for the NMEA parser: a file, a serial device, a TCP stream.
//
// Source is the whole interface (read with a timeout); a host with another
// transport (Bluetooth SPP, a vendor SDK callback) implements it or feeds
// NmeaDecoder directly. The three here are POSIX file descriptors underneath.
//
// Contract:
// - Threads: one thread per instance. close() from another thread is not supported.
// - Errors: nothing throws; open/connect return false with a message, read()
//   returns ReadStatus::Error with error() set.
// - Lifetime: the descriptor is closed by close() or the destructor.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace blvd::gnss {

enum class ReadStatus {
  Data,     // bytes were read
  Timeout,  // nothing arrived within the timeout
  End,      // end of file, peer closed the connection, device hung up
  Error,    // see error()
};

struct ReadResult {
  ReadStatus status = ReadStatus::Error;
  size_t bytes = 0;
};

class Source {
 public:
  virtual ~Source() = default;
  // Waits up to timeout_ms (< 0: no limit) for data and reads at most cap bytes.
  virtual ReadResult read(void* buf, size_t cap, int timeout_ms) = 0;
  // Why the last call failed.
  virtual const std::string& error() const = 0;
};

// A source on a POSIX descriptor, read with poll(2).
class FdSource : public Source {
 public:
  FdSource() = default;
  ~FdSource() override;
  FdSource(const FdSource&) = delete;
  FdSource& operator=(const FdSource&) = delete;

  ReadResult read(void* buf, size_t cap, int timeout_ms) override;
  const std::string& error() const override { return error_; }
  // Writes all bytes (waiting up to timeout_ms in total); false and error() on failure.
  bool writeAll(const void* data, size_t size, int timeout_ms);
  virtual void close();
  bool isOpen() const { return fd_ >= 0; }
  int fd() const { return fd_; }

 protected:
  int fd_ = -1;
  std::string error_;
};

// A regular file (or a FIFO, or "-" for standard input). Reads until the end.
class FileSource final : public FdSource {
 public:
  bool open(const std::string& path, std::string* err);
};

// A serial device in raw mode (8N1, no flow control, no echo, no line editing).
class SerialSource final : public FdSource {
 public:
  // Standard rates 1200..921600; anything else fails.
  bool open(const std::string& device, int baud, std::string* err);
  // Restores the device's previous terminal settings.
  void close() override;

 private:
  bool restore_ = false;
  unsigned char saved_[128] = {};  // struct termios, kept opaque to keep <termios.h> out of the header
};

// A TCP client connection (an NMEA-over-TCP server, or gpsd).
class TcpSource final : public FdSource {
 public:
  // host: a name or numeric address; connect waits at most timeout_ms.
  bool connect(const std::string& host, uint16_t port, int timeout_ms, std::string* err);
};

}  // namespace blvd::gnss
