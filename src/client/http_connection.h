// The HTTP clients' native transport (http_transport.h) on Boost.Beast: one keep-alive connection with
// several GETs pipelined on it (answers come in request order, RFC 9112 §9.3.2), every connect, write and
// read under a deadline, every answer bounded, and bytes counted on the wire (headers included) and as
// payload apart. Two ways to drive it: synchronously (each call runs the connection's io_context until its
// work is done), or without ever waiting (post / poll / take: the free-running viewer's frame).
#pragma once
#include <memory>
#include <optional>
#include <string>

#include "client/http_transport.h"

namespace pms::client {

class HttpConnection : public HttpTransport {
 public:
  HttpConnection(const HttpUrl& url, const HttpOptions& options = {});
  ~HttpConnection() override;
  HttpConnection(const HttpConnection&) = delete;
  HttpConnection& operator=(const HttpConnection&) = delete;

  // The synchronous pipeline, for a caller that keeps GETs in flight between calls (the receiver-driven
  // client's frame budget) and for get_all: send() writes a GET now, connecting first if need be, and at
  // most options.in_flight may be pending; receive() reads the answer to the oldest pending one. A server
  // that closes a kept-alive connection gets a new one, with the GETs it did not answer sent again. Throws
  // ConnectionError for a failed connect, a deadline passed, a reset, or an answer over its limits.
  // HTTP/1.1 cannot take a GET back once written: only closing the connection would, so what is sent is read.
  void send(const std::string& target) override;
  HttpAnswer receive() override;
  size_t pending() const override;
  size_t room() const override;  // GETs send() or post() may still hand over: options.in_flight - pending()

  // The same pipeline for a caller that must never wait (the free-running viewer's frame): post() hands a
  // GET over and returns, connecting in the background if need be; poll() makes the progress the socket
  // allows at once (asio's poll: connect, writes, reads) and take() gives the answers fully arrived, in
  // request order. wait() blocks (under the deadlines) until one has arrived, for a caller that settles.
  // The same limits, deadlines and reconnect as send()/receive(); a lost connection is thrown by the next
  // poll() or wait(). The blocking calls refuse to run while this side has work outstanding.
  void post(const std::string& target) override;
  void poll() override;
  std::optional<HttpAnswer> take() override;
  void wait() override;

  const HttpCounters& counters() const override { return counters_; }

 private:
  void flush();
  struct Impl;
  std::unique_ptr<Impl> impl_;
  HttpCounters counters_;
};

}  // namespace pms::client
