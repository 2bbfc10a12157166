#include "ssh.h"

#include <libssh/callbacks.h>
#include <libssh/libssh.h>

#include <poll.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>

#include "check.h"
#include "clock.h"
#include "crypto.h"
#include "source.h"

namespace {

// The last non-empty line of what a remote process wrote on stderr, short
// enough for a one-line message.
std::string LastLine(const std::string& text) {
  size_t end = text.find_last_not_of(" \t\r\n");
  if (end == std::string::npos) return "";
  size_t begin = text.rfind('\n', end);
  begin = begin == std::string::npos ? 0 : begin + 1;
  std::string line = text.substr(begin, end + 1 - begin);
  if (line.size() > 200) line = line.substr(0, 200) + "...";
  return line;
}

// One ssh connection, shared by the Conns of its channels and closed with
// the last of them.
class Session {
 public:
  Session() : s_(ssh_new()) {}
  ~Session() {
    if (connected_ && !broken_) ssh_blocking_flush(s_, 1000);  // the last bye and EOFs
    if (connected_) ssh_disconnect(s_);
    if (s_) ssh_free(s_);
  }
  ssh_session get() const { return s_; }
  void Connected() { connected_ = true; }
  // The connection failed: do not wait for it to take the last bytes.
  void Broken() { broken_ = true; }

 private:
  ssh_session s_;
  bool connected_ = false, broken_ = false;
};

// One worker process on a channel of a Session. The channel's callbacks
// move what arrives into in_ (and the tail of stderr into err_), so that
// Buffered() knows without reading the socket whether a sibling channel's
// read brought something in for this one.
class SshConn : public Conn {
 public:
  SshConn(std::shared_ptr<Session> session, ssh_channel ch)
      : session_(std::move(session)), ch_(ch) {
    ssh_callbacks_init(&cb_);
    cb_.userdata = this;
    cb_.channel_data_function = OnData;
    cb_.channel_eof_function = OnEof;
    cb_.channel_close_function = OnClose;
    cb_.channel_exit_status_function = OnExitStatus;
    cb_.channel_exit_signal_function = OnExitSignal;
    ssh_set_channel_callbacks(ch_, &cb_);
  }
  ~SshConn() override { Close(true); }
  int fd() const override { return ssh_get_fd(session_->get()); }
  short Events(bool writing) override;
  bool Buffered() override { return in_pos_ < in_.size() || eof_; }
  long Read(char* buf, size_t n) override;
  long Write(const char* buf, size_t n) override;
  void Hangup() override;
  bool Ended() override;
  std::string Reap() override;

 private:
  long Fail() {
    if (!ssh_is_connected(session_->get())) session_->Broken();
    errno = ECONNRESET;
    return -1;
  }
  static int OnData(ssh_session, ssh_channel, void* data, uint32_t len, int is_stderr,
                    void* self) {
    SshConn* c = static_cast<SshConn*>(self);
    std::string& to = is_stderr ? c->err_ : c->in_;
    to.append(static_cast<const char*>(data), len);
    if (is_stderr && to.size() > 4096) to.erase(0, to.size() - 4096);
    return int(len);  // all taken: libssh's buffer stays empty
  }
  static void OnEof(ssh_session, ssh_channel, void* self) { static_cast<SshConn*>(self)->eof_ = true; }
  static void OnClose(ssh_session, ssh_channel, void* self) {
    SshConn* c = static_cast<SshConn*>(self);
    c->eof_ = c->closed_ = true;
  }
  static void OnExitStatus(ssh_session, ssh_channel, int status, void* self) {
    static_cast<SshConn*>(self)->exit_status_ = status;
  }
  static void OnExitSignal(ssh_session, ssh_channel, const char* signal, int, const char*,
                           const char*, void* self) {
    static_cast<SshConn*>(self)->exit_signal_ = signal ? signal : "?";
  }

  std::shared_ptr<Session> session_;
  ssh_channel ch_;
  ssh_channel_callbacks_struct cb_{};  // unset callbacks must be null
  std::string in_, err_;
  size_t in_pos_ = 0;
  bool eof_ = false, closed_ = false;
  int exit_status_ = -1;
  std::string exit_signal_;
};

short SshConn::Events(bool writing) {
  // Pushes what the session holds, as far as the socket takes it; the
  // rest waits for POLLOUT. (ssh_get_poll_flags would keep saying
  // "write pending" after a flush done this way.)
  const bool pending = ssh_blocking_flush(session_->get(), 0) == SSH_AGAIN;
  short ev = POLLIN;
  // A shut window opens with a packet from the server: POLLIN.
  if (pending || (writing && ssh_channel_window_size(ch_) > 0)) ev |= POLLOUT;
  return ev;
}

long SshConn::Read(char* buf, size_t n) {
  // Reads the socket without blocking; the callbacks fill in_ (and the
  // siblings' buffers).
  if (in_pos_ == in_.size() && !eof_ && ssh_channel_poll(ch_, 0) == SSH_ERROR) return Fail();
  if (in_pos_ < in_.size()) {
    const size_t k = std::min(n, in_.size() - in_pos_);
    std::memcpy(buf, in_.data() + in_pos_, k);
    in_pos_ += k;
    if (in_pos_ == in_.size()) {
      in_.clear();
      in_pos_ = 0;
    }
    return long(k);
  }
  if (eof_) return 0;
  errno = EAGAIN;
  return -1;
}

long SshConn::Write(const char* buf, size_t n) {
  // Within the window ssh_channel_write does not wait for the server.
  const uint32_t window = ssh_channel_window_size(ch_);
  if (window == 0) {
    errno = EAGAIN;
    return -1;
  }
  const int rc = ssh_channel_write(ch_, buf, uint32_t(std::min<size_t>({n, window, 1u << 20})));
  if (rc == SSH_ERROR) return Fail();
  if (rc == 0) {  // a key exchange in progress
    errno = EAGAIN;
    return -1;
  }
  return rc;
}

// The worker exits at the end of its input, and says how.
void SshConn::Hangup() {
  if (ch_ && !closed_ && ssh_is_connected(session_->get())) ssh_channel_send_eof(ch_);
}

bool SshConn::Ended() {
  auto ended = [&] {
    return !ch_ || exit_status_ >= 0 || !exit_signal_.empty() || closed_ ||
           !ssh_is_connected(session_->get());
  };
  if (ended()) return true;
  ssh_channel_get_exit_status(ch_);  // reads what came, without blocking
  return ended();
}

std::string SshConn::Reap() {
  if (!ch_) return "";
  ssh_session s = session_->get();
  // sshd passes the signal to the worker's process group: a stopped or
  // hung worker ends too, not only one that reads its input.
  if (!Ended()) ssh_channel_request_send_signal(ch_, "KILL");
  ssh_remove_channel_callbacks(ch_, &cb_);
  ssh_channel_close(ch_);
  ssh_channel_free(ch_);
  ch_ = nullptr;
  std::string how;
  if (exit_status_ >= 0)
    how = DescribeExit(exit_status_);
  else if (!exit_signal_.empty())
    how = "killed by signal " + exit_signal_;
  else if (!ssh_is_connected(s))
    how = std::string("connection lost: ") + ssh_get_error(s);
  const std::string last = LastLine(err_);
  if (!last.empty()) how += (how.empty() ? "" : ": ") + last;
  return how;
}

// This executable, to copy to hosts that have no cmd=.
struct SelfImage {
  std::string bytes;
  std::string sha256;  // hex
};

bool ReadSelf(SelfImage* self, std::string* err) {
  std::ifstream in("/proc/self/exe", std::ios::binary);
  std::ostringstream data;
  if (!(in && data << in.rdbuf())) {
    *err = std::string("cannot read this program (/proc/self/exe): ") + std::strerror(errno);
    return false;
  }
  self->bytes = data.str();
  self->sha256 = Hex(Sha256Of(self->bytes));
  return true;
}

// The remote side of the upload, for /bin/sh: the binary is kept in the
// remote temporary directory under its checksum and reused when a file of
// ours with that checksum is there; otherwise it says "need", takes the
// bytes on stdin into a new file (set -C: never through a planted
// symlink), checks size and checksum, and moves it into place. Without
// sha256sum on the host nothing can be checked, so it is sent every time.
// One line (csh and fish users' login shells pass it to sh unchanged), no
// single quote.
std::string UploadScript(const SelfImage& self) {
  const std::string size = std::to_string(self.bytes.size());
  return "d=${TMPDIR:-/tmp}; f=$d/radiosity-" + self.sha256.substr(0, 16) + "; s=" + self.sha256 +
         "; sum() { command -v sha256sum >/dev/null 2>&1 && sha256sum <\"$1\" | cut -c1-64; }; "
         "if [ -O \"$f\" ] && [ -x \"$f\" ] && [ \"$(sum \"$f\")\" = $s ]; then echo \"have $f\"; exit 0; fi; "
         "echo need; t=$f.$$; umask 077; set -C; "
         "cat >\"$t\" || { rm -f \"$t\"; echo \"error: cannot write $t (no space left?)\"; exit 1; }; "
         "[ $(($(wc -c <\"$t\"))) -eq " + size + " ] || "
         "{ rm -f \"$t\"; echo \"error: $t: incomplete upload (no space left?)\"; exit 1; }; "
         "if command -v sha256sum >/dev/null 2>&1; then [ \"$(sum \"$t\")\" = $s ] || "
         "{ rm -f \"$t\"; echo \"error: $t: checksum differs after the upload\"; exit 1; }; fi; "
         "chmod 700 \"$t\" && mv -f \"$t\" \"$f\" && echo \"have $f\"";
}

// Reads the channel's stdout until a whole line is in *out (true) or the
// end (false), in the session's blocking mode with its timeout.
bool ReadLine(ssh_channel ch, int timeout_ms, std::string* out) {
  char buf[4096];
  while (out->find('\n') == std::string::npos) {
    const int n = ssh_channel_read_timeout(ch, buf, sizeof buf, 0, timeout_ms);
    if (n <= 0) return false;
    out->append(buf, size_t(n));
  }
  return true;
}

// Copies the binary unless the host has it; *path gets its remote path.
bool Upload(ssh_session s, const SelfImage& self, int timeout_ms, bool* sent, std::string* path,
            std::string* err) {
  ssh_channel ch = ssh_channel_new(s);
  if (!ch || ssh_channel_open_session(ch) != SSH_OK) {
    *err = std::string("cannot open a channel for the upload: ") + ssh_get_error(s);
    if (ch) ssh_channel_free(ch);
    return false;
  }
  const std::string cmd = "/bin/sh -c '" + UploadScript(self) + "'";
  std::string out;
  bool ok = ssh_channel_request_exec(ch, cmd.c_str()) == SSH_OK && ReadLine(ch, timeout_ms, &out);
  *sent = ok && out.compare(0, 5, "need\n") == 0;
  if (*sent) {
    out.erase(0, 5);
    for (size_t done = 0; ok && done < self.bytes.size();) {
      const int n = ssh_channel_write(ch, self.bytes.data() + done,
                                      uint32_t(std::min<size_t>(self.bytes.size() - done, 1 << 16)));
      ok = n > 0;
      done += size_t(std::max(n, 0));
    }
    ok = ok && ssh_channel_send_eof(ch) == SSH_OK && ReadLine(ch, timeout_ms, &out);
  }
  std::string why = LastLine(out);
  // Until its process has exited, sshd counts the channel against
  // MaxSessions, even once closed: wait for that (the exit status) before
  // the workers' channels are opened.
  if (ok) ssh_channel_get_exit_status(ch);
  ssh_channel_close(ch);
  ssh_channel_free(ch);
  if (ok && why.compare(0, 5, "have ") == 0 && why.find('\'') == std::string::npos) {
    *path = why.substr(5);
    return true;
  }
  if (why.compare(0, 7, "error: ") == 0) why.erase(0, 7);
  *err = "cannot copy this program to the host: " +
         (why.empty() ? std::string(ssh_get_error(s)) : why);
  return false;
}

// The slots of each host are expected until its thread has delivered.
class SshLauncher : public ThreadedSource {
 public:
  SshLauncher(const std::vector<HostSpec>& hosts, const SshOptions& opts, Note note);
  ~SshLauncher() override { Stop(); }
  void Stop() override;

 private:
  void Run(size_t i);  // on host i's thread
  bool Connect(const HostSpec& h, std::shared_ptr<Session>* out, std::string* err);
  bool CheckHostKey(ssh_session s, std::vector<std::string>* notes, std::string* err);

  std::vector<HostSpec> hosts_;
  SshOptions opts_;
  SelfImage self_;
  std::string self_err_;
  std::vector<std::thread> threads_;
  std::atomic<bool> stop_{false};
  bool stopped_ = false;
};

int Slots(const std::vector<HostSpec>& hosts) {
  int n = 0;
  for (const HostSpec& h : hosts) n += h.slots;
  return n;
}

SshLauncher::SshLauncher(const std::vector<HostSpec>& hosts, const SshOptions& opts, Note note)
    : ThreadedSource(std::move(note), Slots(hosts)), hosts_(hosts), opts_(opts) {
  ssh_init();  // once, before the threads use libssh
  bool upload = false;
  for (const HostSpec& h : hosts_) {
    CHECK(!h.Local());
    upload |= h.cmd.empty();
  }
  if (upload) ReadSelf(&self_, &self_err_);
  for (size_t i = 0; i < hosts_.size(); ++i) threads_.emplace_back([this, i] { Run(i); });
}

void SshLauncher::Stop() {
  if (stopped_) return;
  stopped_ = true;
  stop_ = true;
  for (std::thread& t : threads_) t.join();  // each gives up at its next step
  Drop();  // channels not yet taken: their workers are stopped
}

bool SshLauncher::CheckHostKey(ssh_session s, std::vector<std::string>* notes, std::string* err) {
  std::string fingerprint = "?";
  ssh_key key = nullptr;
  if (ssh_get_server_publickey(s, &key) == SSH_OK) {
    unsigned char* hash = nullptr;
    size_t len = 0;
    if (ssh_get_publickey_hash(key, SSH_PUBLICKEY_HASH_SHA256, &hash, &len) == 0) {
      char* text = ssh_get_fingerprint_hash(SSH_PUBLICKEY_HASH_SHA256, hash, len);
      if (text) fingerprint = std::string(ssh_key_type_to_char(ssh_key_type(key))) + " " + text;
      ssh_string_free_char(text);
      ssh_clean_pubkey_hash(&hash);
    }
    ssh_key_free(key);
  }
  switch (ssh_session_is_known_server(s)) {
    case SSH_KNOWN_HOSTS_OK:
      return true;
    case SSH_KNOWN_HOSTS_CHANGED:
    case SSH_KNOWN_HOSTS_OTHER:
      *err = "host key refused: it differs from the one in known_hosts (now " + fingerprint +
             "): someone may be intercepting the connection, or the host was reinstalled; if "
             "you know the new key is right, remove the old one with ssh-keygen -R";
      return false;
    case SSH_KNOWN_HOSTS_NOT_FOUND:
    case SSH_KNOWN_HOSTS_UNKNOWN:
      if (!opts_.accept_new_host_keys) {
        *err = "host key refused: unknown (" + fingerprint +
               ", not in known_hosts); check it and record it with ssh once, or run with "
               "--accept-new-host-keys";
        return false;
      }
      if (ssh_session_update_known_hosts(s) != SSH_OK) {
        *err = std::string("cannot record the new host key in known_hosts: ") + ssh_get_error(s);
        return false;
      }
      notes->push_back("new host key " + fingerprint + " recorded in known_hosts");
      return true;
    case SSH_KNOWN_HOSTS_ERROR:
      break;
  }
  *err = std::string("cannot check the host key: ") + ssh_get_error(s);
  return false;
}

bool SshLauncher::Connect(const HostSpec& h, std::shared_ptr<Session>* out, std::string* err) {
  auto session = std::make_shared<Session>();
  ssh_session s = session->get();
  if (!s) {
    *err = "cannot make an ssh session";
    return false;
  }
  // ~/.ssh/config first, then what the hosts file says on top of it. The
  // ssh directory follows $HOME (libssh alone would take the password
  // database's home), so that a test or a user can point it elsewhere.
  ssh_options_set(s, SSH_OPTIONS_HOST, h.name.c_str());
  const char* home = std::getenv("HOME");
  if (home && *home) ssh_options_set(s, SSH_OPTIONS_SSH_DIR, (std::string(home) + "/.ssh").c_str());
  if (ssh_options_parse_config(s, nullptr) != 0) {
    *err = std::string("cannot read the ssh configuration: ") + ssh_get_error(s);
    return false;
  }
  if (!h.user.empty()) ssh_options_set(s, SSH_OPTIONS_USER, h.user.c_str());
  if (h.port) {
    const unsigned int port = unsigned(h.port);
    ssh_options_set(s, SSH_OPTIONS_PORT, &port);
  }
  const long timeout = long(std::ceil(opts_.timeout_s));
  ssh_options_set(s, SSH_OPTIONS_TIMEOUT, &timeout);
  if (ssh_connect(s) != SSH_OK) {
    *err = std::string("cannot connect: ") + ssh_get_error(s);
    return false;
  }
  session->Connected();
  std::vector<std::string> notes;
  if (!CheckHostKey(s, &notes, err)) return false;
  const int rc = ssh_userauth_publickey_auto(s, nullptr, nullptr);
  if (rc != SSH_AUTH_SUCCESS) {
    char* user = nullptr;
    ssh_options_get(s, SSH_OPTIONS_USER, &user);
    *err = "authentication as " + std::string(user ? user : "?") + " failed: " +
           (rc == SSH_AUTH_ERROR ? std::string(ssh_get_error(s))
                                 : "the host took neither the ssh agent's keys nor the default "
                                   "ones in ~/.ssh (is the public key in the host's "
                                   "~/.ssh/authorized_keys?)");
    ssh_string_free_char(user);
    return false;
  }
  *out = session;
  return true;
}

void SshLauncher::Run(size_t i) {
  const HostSpec& h = hosts_[i];
  struct {
    std::vector<std::unique_ptr<SshConn>> conns;
    std::vector<std::string> notes;  // for -v
    std::string error;               // a warning: the host, or some of its slots, failed
  } r;
  const double t0 = MonotonicSeconds();
  std::shared_ptr<Session> session;
  std::string path = h.cmd;
  if (h.cmd.empty() && !self_err_.empty()) {
    r.error = self_err_;
  } else if (Connect(h, &session, &r.error)) {
    char line[200];
    std::snprintf(line, sizeof line, "connected in %.2f s", MonotonicSeconds() - t0);
    r.notes.push_back(line);
    const int timeout_ms = int(1000 * opts_.timeout_s);
    bool sent = false;
    const double t1 = MonotonicSeconds();
    if (h.cmd.empty() && !stop_ &&
        Upload(session->get(), self_, timeout_ms, &sent, &path, &r.error)) {
      std::snprintf(line, sizeof line, "%s %s (%.1f MB) in %.2f s", sent ? "copied" : "reusing",
                    path.c_str(), self_.bytes.size() / 1e6, MonotonicSeconds() - t1);
      r.notes.push_back(line);
    }
    // The uploaded path is quoted; cmd= is the user's, for the login
    // shell to expand (~, $HOME).
    const std::string exec =
        h.cmd.empty() ? "exec '" + path + "' --worker" : "exec " + h.cmd + " --worker";
    int on_session = 0;
    while (r.error.empty() && !stop_ && int(r.conns.size()) < h.slots) {
      ssh_channel ch = ssh_channel_new(session->get());
      if (ch && ssh_channel_open_session(ch) == SSH_OK) {
        auto conn = std::make_unique<SshConn>(session, ch);
        if (ssh_channel_request_exec(ch, exec.c_str()) != SSH_OK) {
          r.error = std::string("cannot start a worker: ") + ssh_get_error(session->get());
          break;
        }
        r.conns.push_back(std::move(conn));
        ++on_session;
        continue;
      }
      if (ch) ssh_channel_free(ch);
      if (on_session == 0) {
        r.error = std::string("cannot open a channel: ") + ssh_get_error(session->get());
        break;
      }
      // The server takes no more channels on this connection (sshd's
      // MaxSessions): another connection for the rest.
      r.notes.push_back("the host allows " + std::to_string(on_session) +
                        " channels per connection (MaxSessions): opening another");
      ssh_set_blocking(session->get(), 0);
      if (!Connect(h, &session, &r.error)) break;
      on_session = 0;
    }
    if (session) ssh_set_blocking(session->get(), 0);  // from now on in the pool's poll loop
  }
  session.reset();
  if (stop_) return;
  Delivery d;
  d.settled = h.slots;
  for (const std::string& n : r.notes) d.notes.emplace_back(h.Label() + ": " + n, false);
  if (!r.error.empty())
    d.notes.emplace_back(h.Label() + ": " + r.error +
                             (r.conns.empty() ? "; skipped"
                                              : "; " + std::to_string(r.conns.size()) + " of " +
                                                    std::to_string(h.slots) + " workers started"),
                         true);
  for (size_t k = 0; k < r.conns.size(); ++k)
    d.workers.emplace_back(std::move(r.conns[k]), h.Label() + " worker " + std::to_string(k + 1));
  Deliver(std::move(d));
}

}  // namespace

std::unique_ptr<WorkerSource> StartSshHosts(const std::vector<HostSpec>& hosts,
                                            const SshOptions& opts,
                                            std::function<void(const std::string&, bool)> note) {
  return std::make_unique<SshLauncher>(hosts, opts, std::move(note));
}
