#include "server/http/wire_messages.hpp"

#include <cstdint>
#include <filesystem>
#include <optional>
#include <sstream>

#include <boost/beast/http/empty_body.hpp>
#include <boost/beast/http/write.hpp>

#include <spdlog/spdlog.h>

#include "server/http/http_errors.hpp"

namespace tessera {

namespace http = boost::beast::http;

namespace {

template <typename Message>
void fill_header(Message& message, const HttpResponse& response, bool close_after) {
  message.version(11);
  message.result(static_cast<unsigned>(response.status));
  message.set(http::field::server, "tessera");
  if (!response.content_type.empty() && !has_no_body(response.status))
    message.set(http::field::content_type, response.content_type);
  for (auto& [name, value] : response.headers) message.insert(name, value);
  message.keep_alive(!close_after);
}

}  // namespace

std::string stream_header(const HttpResponse& response) {
  http::response<http::empty_body> message;
  fill_header(message, response, true);
  std::ostringstream text;
  text << message.base();
  return text.str();
}

RequestHead head_of(const BeastRequest& request) {
  RequestHead head;
  head.method = std::string_view(request.method_string().data(), request.method_string().size());
  head.version = request.version();
  head.target = std::string_view(request.target().data(), request.target().size());
  for (const auto& field : request)
    head.fields.push_back({std::string_view(field.name_string().data(), field.name_string().size()),
                           std::string_view(field.value().data(), field.value().size())});
  return head;
}

HttpRequest plain_request(BeastRequest& request) {
  HttpRequest plain;
  plain.method = std::string(request.method_string());
  for (const auto& field : request) {
    auto [it, inserted] = plain.headers.try_emplace(
        ascii_lower({field.name_string().data(), field.name_string().size()}), field.value());
    if (!inserted) it->second.append(", ").append(field.value().data(), field.value().size());
  }
  plain.body = std::move(request.body());
  return plain;
}

WireMessage response_message(HttpResponse response, bool head_only, bool close_after,
                             std::string_view where) {
  std::optional<std::uint64_t> file_size;  // for HEAD, which announces the file unsent
  if (!response.file.empty() && !has_no_body(response.status)) {
    http::file_body::value_type file;
    boost::beast::error_code ec;
    file.open(response.file.c_str(), boost::beast::file_mode::scan, ec);
    if (response.file_is_temporary) {
      std::error_code ignored;
      std::filesystem::remove(response.file, ignored);
    }
    if (!ec && !head_only) {
      FileMessage message;
      fill_header(message, response, close_after);
      message.body() = std::move(file);
      message.prepare_payload();
      return message;
    }
    if (ec) {
      spdlog::error("http {}: cannot open {} to answer: {}", where, response.file, ec.message());
      response = error_response(500, "internal_error", "the answer's file cannot be read");
    } else {
      file_size = file.size();
    }
  }
  StringMessage message;
  fill_header(message, response, close_after);
  if (has_no_body(response.status)) return message;
  if (head_only) {
    message.content_length(file_size.value_or(response.body.size()));
  } else {
    message.body() = std::move(response.body);
    message.prepare_payload();
  }
  return message;
}

}  // namespace tessera
