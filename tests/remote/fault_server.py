#!/usr/bin/env python3
"""An HTTP server that misbehaves the way a car's link and a careless server do,
for the range client's tests. Serves the files of ROOT under /<fault>/<name>:

  ok        ranges as a server should (206, ETag, If-Match -> 412)
  cut       the first answer to each range is cut mid-body, then as ok
  full200   ignores Range: 200 with the whole file
  retry503  the first request answers 503 with Retry-After: 1, then as ok
  stall     the first request sends nothing for 3 s, then as ok
  etag      ETag "v1" for the first 2 requests, then "v2" (If-Match "v1" -> 412)
  drive     a drive's link: of every 13 requests, the 4th is cut mid-body, the 7th
            answered 200 with the whole file, the 10th 503 with Retry-After: 1;
            and while ROOT/.down exists, a request is accepted and answered
            with nothing (a tunnel) until the file goes

Usage: fault_server.py ROOT PORT_FILE  (binds a free loopback port, writes it to
PORT_FILE, serves until killed)."""
import http.server
import os
import re
import socketserver
import sys
import threading
import time

ROOT = sys.argv[1]
seen = {}
lock = threading.Lock()


def count(key):
    with lock:
        seen[key] = seen.get(key, 0) + 1
        return seen[key]


class Handler(http.server.BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.0"

    def log_message(self, *args):
        pass

    def do_GET(self):
        m = re.match(r"^/(\w+)/([\w.\-]+)$", self.path)
        if not m or not os.path.isfile(os.path.join(ROOT, m.group(2))):
            self.send_error(404)
            return
        fault, name = m.groups()
        data = open(os.path.join(ROOT, name), "rb").read()
        n = count((fault, name, self.headers.get("Range")))
        total = count((fault, name))
        etag = '"v1"'
        k = total % 13
        if fault == "drive":
            while os.path.exists(os.path.join(ROOT, ".down")):
                time.sleep(0.2)
                if not os.path.exists(os.path.join(ROOT, ".down")):
                    self.connection.shutdown(2)  # the tunnel's end: this request is lost
                    return
        if fault == "drive" and k == 10:
            self.send_response(503)
            self.send_header("Retry-After", "1")
            self.send_header("Content-Length", "0")
            self.end_headers()
            return
        if fault == "etag":
            etag = '"v1"' if total <= 2 else '"v2"'
        if fault == "retry503" and total == 1:
            self.send_response(503)
            self.send_header("Retry-After", "1")
            self.send_header("Content-Length", "0")
            self.end_headers()
            return
        if fault == "stall" and total == 1:
            time.sleep(3)
        want = self.headers.get("If-Match")
        if want and want != etag:
            self.send_response(412)
            self.send_header("Content-Length", "0")
            self.end_headers()
            return
        rng = re.match(r"bytes=(\d+)-(\d+)$", self.headers.get("Range", ""))
        if rng and fault != "full200" and not (fault == "drive" and k == 7):
            a, b = int(rng.group(1)), min(int(rng.group(2)), len(data) - 1)
            body = data[a:b + 1]
            self.send_response(206)
            self.send_header("Content-Range", "bytes %d-%d/%d" % (a, b, len(data)))
        else:
            body = data
            self.send_response(200)
        self.send_header("ETag", etag)
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        if (fault == "cut" and n == 1) or (fault == "drive" and k == 4):
            self.wfile.write(body[:len(body) // 2])
            self.wfile.flush()
            self.connection.shutdown(2)
            return
        self.wfile.write(body)


class Server(socketserver.ThreadingMixIn, http.server.HTTPServer):
    daemon_threads = True


server = Server(("127.0.0.1", 0), Handler)
with open(sys.argv[2] + ".tmp", "w") as f:
    f.write(str(server.server_address[1]))
os.rename(sys.argv[2] + ".tmp", sys.argv[2])
server.serve_forever()
