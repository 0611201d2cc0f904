// Real servers for the remote tests, started and stopped by the tests:
// nginx (Debian's) with a configuration in a temporary folder, and
// fault_server.py. Each on a free loopback port.
#pragma once
#include <string>
#include <vector>

namespace blvd::test {

class ServerProcess {
 public:
  ServerProcess() = default;
  ~ServerProcess() { stop(); }
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  // nginx serving `root` at /, and at /slow/ with limit_rate `slow_bytes_per_s`.
  // False (with `why`) when nginx is missing or does not answer.
  bool startNginx(const std::string& work, const std::string& root, int slow_bytes_per_s, std::string& why);
  // tests/remote/fault_server.py serving `root`.
  bool startFaultServer(const std::string& work, const std::string& root, std::string& why);
  void stop();

  int port() const { return port_; }
  std::string url(const std::string& path) const { return "http://127.0.0.1:" + std::to_string(port_) + path; }

 private:
  bool spawn(const std::string& program, const std::vector<std::string>& args, std::string& why);
  int pid_ = -1, port_ = 0;
};

// A loopback port nobody listens on now.
int freePort();

}  // namespace blvd::test
