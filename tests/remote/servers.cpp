// Real servers for the remote tests; see servers.h.
#include "servers.h"

#include <chrono>
#include <fstream>
#include <functional>
#include <thread>
#include <vector>

#include <arpa/inet.h>
#include <csignal>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

namespace blvd::test {
namespace {

bool answers(int port) {
  const int s = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(uint16_t(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool ok = ::connect(s, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  ::close(s);
  return ok;
}

bool waitFor(const std::function<bool()>& ready) {
  for (int i = 0; i < 100; ++i) {
    if (ready()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return false;
}

}  // namespace

int freePort() {
  const int s = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  ::bind(s, reinterpret_cast<sockaddr*>(&a), sizeof a);
  ::getsockname(s, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(s);
  return ntohs(a.sin_port);
}

bool ServerProcess::spawn(const std::string& program, const std::vector<std::string>& args, std::string& why) {
  std::vector<char*> argv{const_cast<char*>(program.c_str())};
  for (const std::string& s : args) argv.push_back(const_cast<char*>(s.c_str()));
  argv.push_back(nullptr);
  pid_ = ::fork();
  if (pid_ == 0) {
    ::execvp(program.c_str(), argv.data());
    ::_exit(127);
  }
  if (pid_ < 0) return why = "fork failed", false;
  return true;
}

bool ServerProcess::startNginx(const std::string& work, const std::string& root, int slow_bytes_per_s,
                               std::string& why) {
  port_ = freePort();
  std::ofstream(work + "/nginx.conf")
      << "daemon off;\nmaster_process off;\nuser root;\npid " << work << "/nginx.pid;\nerror_log " << work
      << "/error.log;\nevents { worker_connections 64; }\nhttp {\n  access_log " << work << "/access.log;\n"
      << "  client_body_temp_path " << work << "/body;\n  proxy_temp_path " << work << "/proxy;\n"
      << "  fastcgi_temp_path " << work << "/fastcgi;\n  uwsgi_temp_path " << work << "/uwsgi;\n"
      << "  scgi_temp_path " << work << "/scgi;\n  server {\n    listen 127.0.0.1:" << port_ << ";\n"
      << "    root " << root << ";\n    location /slow/ { alias " << root << "/; limit_rate " << slow_bytes_per_s
      << "; }\n  }\n}\n";
  const char* nginx = ::access("/usr/sbin/nginx", X_OK) == 0 ? "/usr/sbin/nginx" : "nginx";  // sbin may be off PATH
  if (!spawn(nginx, {"-p", work, "-c", work + "/nginx.conf"}, why)) return false;
  if (!waitFor([&] { return answers(port_); })) return stop(), why = "nginx did not answer (see " + work + "/error.log)", false;
  return true;
}

bool ServerProcess::startFaultServer(const std::string& work, const std::string& root, std::string& why) {
  const std::string port_file = work + "/fault.port";
  ::unlink(port_file.c_str());
  if (!spawn("python3", {BLVD_REMOTE_TEST_DIR "/fault_server.py", root, port_file}, why)) return false;
  if (!waitFor([&] { return ::access(port_file.c_str(), R_OK) == 0; }))
    return stop(), why = "fault_server.py did not start", false;
  std::ifstream(port_file) >> port_;
  return waitFor([&] { return answers(port_); }) || (stop(), why = "fault_server.py does not answer", false);
}

void ServerProcess::stop() {
  if (pid_ <= 0) return;
  ::kill(pid_, SIGTERM);
  ::waitpid(pid_, nullptr, 0);
  pid_ = -1;
}

}  // namespace blvd::test
