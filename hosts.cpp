#include "hosts.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <sstream>

#include "files.h"

namespace {

// A decimal number in [lo, hi], nothing else (no sign, no spaces).
bool Decimal(const std::string& s, long lo, long hi, int* out) {
  if (s.empty() || s.size() > 9) return false;
  long v = 0;
  for (char c : s) {
    if (c < '0' || c > '9') return false;
    v = 10 * v + (c - '0');
  }
  if (v < lo || v > hi) return false;
  *out = int(v);
  return true;
}

// Characters of a host name or address: letters, digits, '.', '-', '_'
// (and ':' '%' inside brackets). Anything else is a typo or an attempt to
// smuggle shell or ssh option syntax in.
bool NameChar(char c, bool bracketed) {
  if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9')) return true;
  if (c == '.' || c == '-' || c == '_') return true;
  return bracketed && (c == ':' || c == '%');
}

bool UserChar(char c) { return NameChar(c, false) || c == '$'; }

// The first word: [user@]name[:port].
bool ParseHost(const std::string& word, HostSpec* h, std::string* err) {
  std::string rest = word;
  const size_t at = rest.rfind('@');
  if (at != std::string::npos) {
    h->user = rest.substr(0, at);
    rest = rest.substr(at + 1);
    if (h->user.empty()) { *err = "empty user name before '@' in '" + word + "'"; return false; }
    for (char c : h->user)
      if (!UserChar(c)) { *err = "bad character '" + std::string(1, c) + "' in user name '" + h->user + "'"; return false; }
  }
  std::string port;
  bool has_port = false, bracketed = false;
  if (!rest.empty() && rest[0] == '[') {
    const size_t close = rest.find(']');
    if (close == std::string::npos) { *err = "missing ']' after IPv6 address in '" + word + "'"; return false; }
    h->name = rest.substr(1, close - 1);
    bracketed = true;
    // Brackets hold an IPv6 address (with ':'): a name in them would lose
    // them in FormatHost and read back as something else (fuzz/hosts_fuzz).
    if (h->name.find(':') == std::string::npos) {
      *err = "brackets are for IPv6 addresses, not '" + word + "'";
      return false;
    }
    rest = rest.substr(close + 1);
    if (!rest.empty() && rest[0] != ':') { *err = "expected ':port' after ']' in '" + word + "'"; return false; }
    has_port = !rest.empty();
    if (has_port) port = rest.substr(1);
  } else {
    if (std::count(rest.begin(), rest.end(), ':') > 1) {
      *err = "write an IPv6 address in brackets, [addr] or [addr]:port, not '" + word + "'";
      return false;
    }
    const size_t colon = rest.find(':');
    h->name = rest.substr(0, colon);
    has_port = colon != std::string::npos;
    if (has_port) port = rest.substr(colon + 1);
  }
  if (h->name.empty()) { *err = "empty host name in '" + word + "'"; return false; }
  for (char c : h->name)
    if (!NameChar(c, bracketed)) {
      *err = "bad character '" + std::string(1, c) + "' in host name '" + h->name + "'";
      return false;
    }
  if (has_port && !Decimal(port, 1, 65535, &h->port)) {
    *err = "bad port '" + port + "' in '" + word + "' (must be 1 to 65535)";
    return false;
  }
  if (h->Local() && (!h->user.empty() || h->port)) {
    *err = "localhost forks workers on this machine without ssh, so it takes no user@ or :port "
           "(write 127.0.0.1 to use ssh to this machine)";
    return false;
  }
  return true;
}

bool ParseLine(const std::string& line, HostSpec* h, std::string* err) {
  std::istringstream words(line);
  std::string word;
  words >> word;
  if (word.find('=') != std::string::npos && word.find('@') == std::string::npos) {
    *err = "expected [user@]host[:port] before '" + word + "'";
    return false;
  }
  if (!ParseHost(word, h, err)) return false;
  bool have_slots = false, have_cmd = false;
  while (words >> word) {
    const size_t eq = word.find('=');
    if (eq == std::string::npos) { *err = "expected key=value, got '" + word + "'"; return false; }
    const std::string key = word.substr(0, eq), value = word.substr(eq + 1);
    if (key == "slots") {
      if (have_slots) { *err = "slots= given twice"; return false; }
      have_slots = true;
      if (!Decimal(value, 1, kMaxSlots, &h->slots)) {
        *err = "bad slots '" + value + "' (must be 1 to " + std::to_string(kMaxSlots) + ")";
        return false;
      }
    } else if (key == "cmd") {
      if (have_cmd) { *err = "cmd= given twice"; return false; }
      have_cmd = true;
      if (value.empty()) { *err = "empty cmd= (leave it out to upload this binary)"; return false; }
      h->cmd = value;
    } else {
      *err = "unknown key '" + key + "' (expected slots= or cmd=)";
      return false;
    }
  }
  return true;
}

}  // namespace

std::string HostSpec::Label() const {
  std::string s;
  if (!user.empty()) s += user + "@";
  s += name.find(':') != std::string::npos ? "[" + name + "]" : name;
  if (port) s += ":" + std::to_string(port);
  return s;
}

std::string FormatHost(const HostSpec& h) {
  std::string s = h.Label() + " slots=" + std::to_string(h.slots);
  if (!h.cmd.empty()) s += " cmd=" + h.cmd;
  return s;
}

bool ParseHosts(const std::string& text, const std::string& file, std::vector<HostSpec>* hosts,
                std::string* err) {
  std::istringstream in(text);
  std::string line;
  long total = 0;
  for (int n = 1; std::getline(in, line); ++n) {
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    for (char c : line)
      if ((unsigned char)c < 0x20 && c != '\t' && c != '\r') {
        *err = file + ":" + std::to_string(n) + ": control character in line";
        return false;
      }
    HostSpec h;
    h.line = n;
    std::string why;
    if (!ParseLine(line, &h, &why)) {
      *err = file + ":" + std::to_string(n) + ": " + why;
      return false;
    }
    total += h.slots;
    if (total > kMaxTotalSlots) {
      *err = file + ":" + std::to_string(n) + ": more than " + std::to_string(kMaxTotalSlots) +
             " slots in all";
      return false;
    }
    hosts->push_back(h);
  }
  return true;
}

bool ReadHosts(const std::string& file, std::vector<HostSpec>* hosts, std::string* err) {
  std::string text;
  if (!ReadInput(file, kMaxHostsBytes, &text, err)) return false;
  if (!ParseHosts(text, file, hosts, err)) return false;
  if (hosts->empty()) {
    *err = file + ": lists no host";
    return false;
  }
  return true;
}
