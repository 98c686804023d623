#include "server/http/request_framing.hpp"

#include <string>

#include "common/protocol/limits.hpp"

namespace tessera {

namespace {

HttpResponse target_too_long(std::size_t max_target_bytes) {
  return error_response(
      414, "uri_too_long",
      "the request target exceeds " + with_thousands(max_target_bytes) + " bytes");
}

HttpResponse bad_framing(const std::string& why) { return error_response(400, "bad_request", why); }

// Transfer-Encoding, every field of it taken together as one list (RFC 9110 5.3).
std::optional<HttpResponse> transfer_coding_problem(const RequestHead& head) {
  std::vector<std::string_view> codings;
  bool has_length = false;
  bool has_coding = false;
  for (const HeaderField& field : head.fields) {
    if (iequals_ascii(field.name, "content-length")) has_length = true;
    if (!iequals_ascii(field.name, "transfer-encoding")) continue;
    has_coding = true;
    std::string_view list = field.value;
    while (true) {
      const std::size_t comma = list.find(',');
      codings.push_back(trim_ows(list.substr(0, comma)));
      if (comma == std::string_view::npos) break;
      list.remove_prefix(comma + 1);
    }
  }
  if (!has_coding) return std::nullopt;
  if (head.version < 11)
    return bad_framing("Transfer-Encoding is not allowed in an HTTP/1.0 request");
  if (has_length)
    return bad_framing("a request may not have both Transfer-Encoding and Content-Length");
  for (std::string_view coding : codings)
    if (coding.empty()) return bad_framing("Transfer-Encoding has an empty coding");
  if (!iequals_ascii(codings.back(), "chunked"))
    return bad_framing("Transfer-Encoding must end in chunked, so that the body's end is known");
  for (std::size_t i = 0; i + 1 < codings.size(); ++i) {
    if (iequals_ascii(codings[i], "chunked"))
      return bad_framing("Transfer-Encoding applies chunked more than once");
  }
  if (codings.size() > 1)
    return error_response(501, "not_implemented",
                          "the only transfer coding this server reads is chunked, alone; got '" +
                              std::string(codings.front()) + "' before it");
  return std::nullopt;
}

// A Host value: a reg-name or IP literal with an optional port, no spaces, controls,
// user info or path.
// Empty is allowed: it is what a client sends for a target without an authority.
bool valid_host(std::string_view host) {
  for (char c : host) {
    const auto u = static_cast<unsigned char>(c);
    if (u <= 0x20 || u >= 0x7f || c == '/' || c == '@' || c == '\\' || c == '?' || c == '#')
      return false;
  }
  return true;
}

}  // namespace

std::optional<std::string_view> RequestHead::field(std::string_view name) const {
  for (const HeaderField& f : fields)
    if (iequals_ascii(f.name, name)) return f.value;
  return std::nullopt;
}

std::optional<HttpResponse> raw_header_problem(std::string_view header,
                                               std::size_t max_target_bytes) {
  const std::size_t line_end = header.find("\r\n");
  const std::string_view request_line = header.substr(0, line_end);
  // "METHOD SP target SP HTTP/x.y": the target is what the line holds beyond the rest.
  if (request_line.size() > max_target_bytes + 32) return target_too_long(max_target_bytes);
  if (line_end == std::string_view::npos) return std::nullopt;
  for (std::size_t at = header.find("\r\n"); at != std::string_view::npos;
       at = header.find("\r\n", at + 2)) {
    if (at + 2 >= header.size()) break;
    const char next = header[at + 2];
    if (next == ' ' || next == '\t')
      return bad_framing("a header field line is folded onto the next (obs-fold, RFC 9112 5.2)");
  }
  return std::nullopt;
}

std::optional<HttpResponse> framing_problem(const RequestHead& head, std::size_t max_target_bytes) {
  if (head.target.size() > max_target_bytes) return target_too_long(max_target_bytes);
  int hosts = 0;
  for (const HeaderField& field : head.fields) {
    if (!iequals_ascii(field.name, "host")) continue;
    ++hosts;
    if (!valid_host(field.value)) return bad_framing("the Host header is not a valid host");
  }
  if (hosts > 1) return bad_framing("the request has more than one Host header");
  if (hosts == 0 && head.version >= 11)
    return bad_framing("an HTTP/1.1 request must have a Host header");
  return transfer_coding_problem(head);
}

}  // namespace tessera
