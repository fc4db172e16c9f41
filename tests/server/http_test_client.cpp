// The Beast test client (http_test_client.h).
#include "http_test_client.h"
#include "loopback_socket.h"

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <cctype>
#include <stdexcept>
#include <utility>

namespace pms::test {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using asio::ip::tcp;

struct HttpTestClient::Impl {
  asio::io_context io;
  tcp::socket socket{io};
  beast::flat_buffer buffer;
};

HttpTestClient::HttpTestClient(uint16_t port, int timeout_ms, const std::string& from, int receive_buffer)
    : impl_(std::make_unique<Impl>()) {
  connect_loopback(impl_->socket, port, from, timeout_ms, receive_buffer);
}

HttpTestClient::~HttpTestClient() = default;

namespace {

using ResponseParser = http::response_parser<http::vector_body<uint8_t>>;

HttpReply reply_of(ResponseParser& parser) {
  HttpReply reply;
  reply.status = int(parser.get().result_int());
  for (const auto& field : parser.get()) {
    std::string name(field.name_string());
    for (char& c : name) c = char(std::tolower(static_cast<unsigned char>(c)));
    reply.headers[name] = std::string(field.value());
  }
  reply.body = std::move(parser.get().body());
  return reply;
}

HttpReply send_request(tcp::socket& socket, beast::flat_buffer& buffer,
                       http::request<http::vector_body<uint8_t>>& request) {
  request.set(http::field::host, "127.0.0.1");
  request.prepare_payload();
  http::write(socket, request);
  ResponseParser parser;
  parser.body_limit(64u << 20);
  parser.skip(request.method() == http::verb::head);
  http::read(socket, buffer, parser);
  return reply_of(parser);
}

}  // namespace

HttpReply HttpTestClient::get(const std::string& target, const std::map<std::string, std::string>& headers) {
  http::request<http::vector_body<uint8_t>> request{http::verb::get, target, 11};
  for (const auto& [name, value] : headers) request.set(name, value);
  return send_request(impl_->socket, impl_->buffer, request);
}

HttpReply HttpTestClient::head(const std::string& target) {
  http::request<http::vector_body<uint8_t>> request{http::verb::head, target, 11};
  return send_request(impl_->socket, impl_->buffer, request);
}

HttpReply HttpTestClient::post(const std::string& target, const std::vector<uint8_t>& body) {
  http::request<http::vector_body<uint8_t>> request{http::verb::post, target, 11};
  request.body() = body;
  return send_request(impl_->socket, impl_->buffer, request);
}

void HttpTestClient::send(const std::string& bytes) { asio::write(impl_->socket, asio::buffer(bytes)); }

HttpReply HttpTestClient::read() {
  ResponseParser parser;
  http::read(impl_->socket, impl_->buffer, parser);
  return reply_of(parser);
}

HttpReply HttpTestClient::raw(const std::string& bytes) {
  send(bytes);
  return read();
}

std::optional<std::string> HttpTestClient::rest_until_closed() {
  const auto buffered = impl_->buffer.data();
  std::string rest(static_cast<const char*>(buffered.data()), buffered.size());
  impl_->buffer.consume(buffered.size());
  char chunk[4096];
  for (;;) {
    boost::system::error_code ec;
    rest.append(chunk, impl_->socket.read_some(asio::buffer(chunk), ec));
    if (ec == asio::error::eof || ec == asio::error::connection_reset) return rest;
    if (ec) return std::nullopt;  // the receive timeout: still open
  }
}

bool HttpTestClient::closed_by_server() {
  char byte;
  boost::system::error_code ec;
  for (;;) {
    impl_->socket.read_some(asio::buffer(&byte, 1), ec);
    if (ec == asio::error::eof || ec == asio::error::connection_reset) return true;
    if (ec) return false;  // the receive timeout: still open
  }
}

}  // namespace pms::test
