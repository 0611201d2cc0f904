#include "gnss/source.h"

#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>

namespace blvd::gnss {

static_assert(sizeof(termios) <= 128, "SerialSource::saved_ too small for struct termios");

namespace {

std::string errnoText(const std::string& what) { return what + ": " + std::strerror(errno); }

int remainingMs(std::chrono::steady_clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
  return left.count() < 0 ? 0 : static_cast<int>(left.count());
}

}  // namespace

FdSource::~FdSource() {
  if (fd_ >= 0) ::close(fd_);
}

void FdSource::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

ReadResult FdSource::read(void* buf, size_t cap, int timeout_ms) {
  if (fd_ < 0) {
    error_ = "read: source is not open";
    return {ReadStatus::Error, 0};
  }
  pollfd p{fd_, POLLIN, 0};
  int r;
  do {
    r = ::poll(&p, 1, timeout_ms);
  } while (r < 0 && errno == EINTR);
  if (r < 0) {
    error_ = errnoText("poll");
    return {ReadStatus::Error, 0};
  }
  if (r == 0) return {ReadStatus::Timeout, 0};
  ssize_t n;
  do {
    n = ::read(fd_, buf, cap);
  } while (n < 0 && errno == EINTR);
  if (n > 0) return {ReadStatus::Data, static_cast<size_t>(n)};
  if (n == 0) return {ReadStatus::End, 0};
  if (errno == EAGAIN || errno == EWOULDBLOCK) return {ReadStatus::Timeout, 0};
  // A terminal whose other side went away (USB receiver unplugged, pty master closed).
  if (errno == EIO) {
    error_ = errnoText("read");
    return {ReadStatus::End, 0};
  }
  error_ = errnoText("read");
  return {ReadStatus::Error, 0};
}

bool FdSource::writeAll(const void* data, size_t size, int timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms < 0 ? 0 : timeout_ms);
  const auto* p = static_cast<const char*>(data);
  while (size > 0) {
    ssize_t n;
    do {
      n = ::write(fd_, p, size);
    } while (n < 0 && errno == EINTR);
    if (n > 0) {
      p += n;
      size -= static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK) {
      error_ = errnoText("write");
      return false;
    }
    pollfd pfd{fd_, POLLOUT, 0};
    const int wait = timeout_ms < 0 ? -1 : remainingMs(deadline);
    if (timeout_ms >= 0 && wait == 0) {
      error_ = "write: timed out";
      return false;
    }
    if (::poll(&pfd, 1, wait) < 0 && errno != EINTR) {
      error_ = errnoText("poll");
      return false;
    }
  }
  return true;
}

// ---------------------------------------------------------------------------

bool FileSource::open(const std::string& path, std::string* err) {
  close();
  if (path == "-") {
    fd_ = ::dup(STDIN_FILENO);
  } else {
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  }
  if (fd_ < 0) {
    error_ = errnoText(path);
    if (err) *err = error_;
    return false;
  }
  return true;
}

// ---------------------------------------------------------------------------

namespace {

bool baudConstant(int baud, speed_t* out) {
  switch (baud) {
    case 1200: *out = B1200; return true;
    case 2400: *out = B2400; return true;
    case 4800: *out = B4800; return true;
    case 9600: *out = B9600; return true;
    case 19200: *out = B19200; return true;
    case 38400: *out = B38400; return true;
    case 57600: *out = B57600; return true;
    case 115200: *out = B115200; return true;
    case 230400: *out = B230400; return true;
    case 460800: *out = B460800; return true;
    case 921600: *out = B921600; return true;
    default: return false;
  }
}

}  // namespace

bool SerialSource::open(const std::string& device, int baud, std::string* err) {
  close();
  auto fail = [&](const std::string& msg) {
    error_ = msg;
    if (err) *err = msg;
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    return false;
  };
  speed_t speed;
  if (!baudConstant(baud, &speed)) return fail(device + ": unsupported baud rate " + std::to_string(baud));
  // O_NONBLOCK: do not wait for carrier detect; reads are paced by poll().
  fd_ = ::open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) return fail(errnoText(device));
  if (!::isatty(fd_)) return fail(device + ": not a terminal device");
  termios old{};
  if (::tcgetattr(fd_, &old) != 0) return fail(errnoText(device + ": tcgetattr"));
  termios t = old;
  ::cfmakeraw(&t);  // no echo, no canonical mode, no CR/LF translation, 8 bits
  t.c_cflag |= CLOCAL | CREAD;
  t.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | PARENB | CRTSCTS);
  t.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
  t.c_cc[VMIN] = 1;
  t.c_cc[VTIME] = 0;
  if (::cfsetispeed(&t, speed) != 0 || ::cfsetospeed(&t, speed) != 0)
    return fail(errnoText(device + ": cfsetspeed"));
  if (::tcsetattr(fd_, TCSANOW, &t) != 0) return fail(errnoText(device + ": tcsetattr"));
  std::memcpy(saved_, &old, sizeof old);
  restore_ = true;
  return true;
}

void SerialSource::close() {
  if (fd_ >= 0 && restore_) {
    termios old;
    std::memcpy(&old, saved_, sizeof old);
    (void)::tcsetattr(fd_, TCSANOW, &old);
  }
  restore_ = false;
  FdSource::close();
}

// ---------------------------------------------------------------------------

bool TcpSource::connect(const std::string& host, uint16_t port, int timeout_ms, std::string* err) {
  close();
  const std::string where = host + ":" + std::to_string(port);
  auto fail = [&](const std::string& msg) {
    error_ = msg;
    if (err) *err = msg;
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    return false;
  };
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* res = nullptr;
  const std::string service = std::to_string(port);
  const int gai = ::getaddrinfo(host.c_str(), service.c_str(), &hints, &res);
  if (gai != 0) return fail(where + ": " + ::gai_strerror(gai));
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms < 0 ? 0 : timeout_ms);
  std::string last = where + ": no address";
  for (addrinfo* ai = res; ai; ai = ai->ai_next) {
    fd_ = ::socket(ai->ai_family, ai->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, ai->ai_protocol);
    if (fd_ < 0) {
      last = errnoText(where + ": socket");
      continue;
    }
    int r = ::connect(fd_, ai->ai_addr, ai->ai_addrlen);
    if (r != 0 && errno == EINPROGRESS) {
      pollfd p{fd_, POLLOUT, 0};
      do {
        r = ::poll(&p, 1, timeout_ms < 0 ? -1 : remainingMs(deadline));
      } while (r < 0 && errno == EINTR);
      if (r == 0) {
        last = where + ": connection timed out";
        ::close(fd_);
        fd_ = -1;
        continue;
      }
      int so = 0;
      socklen_t len = sizeof so;
      if (r < 0 || ::getsockopt(fd_, SOL_SOCKET, SO_ERROR, &so, &len) != 0) so = errno;
      if (so != 0) {
        errno = so;
        last = errnoText(where);
        ::close(fd_);
        fd_ = -1;
        continue;
      }
      r = 0;
    }
    if (r != 0) {
      last = errnoText(where);
      ::close(fd_);
      fd_ = -1;
      continue;
    }
    const int one = 1;
    (void)::setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    ::freeaddrinfo(res);
    return true;
  }
  ::freeaddrinfo(res);
  return fail(last);
}

}  // namespace blvd::gnss
