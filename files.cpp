#include "files.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <set>

namespace {

std::string Errno(const std::string& path) { return path + ": " + std::strerror(errno); }

std::string Bytes(uint64_t n) {
  return n >= (1u << 30) && n % (1u << 30) == 0 ? std::to_string(n >> 30) + " GiB"
         : n >= (1u << 20) && n % (1u << 20) == 0 ? std::to_string(n >> 20) + " MiB"
         : n >= (1u << 10) && n % (1u << 10) == 0 ? std::to_string(n >> 10) + " KiB"
                                                  : std::to_string(n) + " bytes";
}

bool WriteAll(int fd, const char* data, size_t size) {
  for (size_t done = 0; done < size;) {
    const ssize_t n = ::write(fd, data + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (n == 0) errno = EIO;
      return false;
    }
    done += size_t(n);
  }
  return true;
}

// The mode a file made by open(O_CREAT, 0666) would get: mkstemp's 0600
// is for the moment the file is being written only.
mode_t CreateMode() {
  const mode_t mask = ::umask(077);
  ::umask(mask);
  return 0666 & ~mask;
}

}  // namespace

int OpenInput(const std::string& path, uint64_t max_bytes, std::string* err, FileId* id) {
  // O_NONBLOCK: opening a FIFO without a writer (or a device) must not
  // block before fstat can refuse it; regular files ignore the flag.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) {
    *err = std::strerror(errno);
    return -1;
  }
  struct stat st;
  if (::fstat(fd, &st) != 0) {
    *err = std::strerror(errno);
  } else if (!S_ISREG(st.st_mode)) {
    *err = "not a regular file";
  } else if (uint64_t(st.st_size) > max_bytes) {
    *err = std::to_string(st.st_size) + " bytes, more than the limit of " + Bytes(max_bytes);
  } else {
    ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
    if (id) *id = {st.st_dev, st.st_ino};
    return fd;
  }
  ::close(fd);
  return -1;
}

std::FILE* OpenInputFile(const std::string& path, uint64_t max_bytes, std::string* err,
                         FileId* id) {
  const int fd = OpenInput(path, max_bytes, err, id);
  if (fd < 0) return nullptr;
  std::FILE* f = ::fdopen(fd, "rb");
  if (!f) {
    *err = std::strerror(errno);
    ::close(fd);
  }
  return f;
}

bool ReadInput(const std::string& path, uint64_t max_bytes, std::string* bytes, std::string* err,
               FileId* id) {
  const int fd = OpenInput(path, max_bytes, err, id);
  if (fd < 0) {
    *err = path + ": " + *err;
    return false;
  }
  bytes->clear();
  char buf[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      *err = path + ": cannot read: " + std::strerror(errno);
      break;
    }
    if (n == 0) {
      ::close(fd);
      return true;
    }
    if (bytes->size() + size_t(n) > max_bytes) {
      *err = path + ": grew past the limit of " + Bytes(max_bytes) + " while read";
      break;
    }
    bytes->append(buf, size_t(n));
  }
  ::close(fd);
  return false;
}

bool AddInput(const std::string& what, const std::string& path, std::vector<Input>* inputs,
              std::string* err) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) {
    *err = Errno(path);
    return false;
  }
  inputs->push_back({what, path, {st.st_dev, st.st_ino}});
  return true;
}

std::string Unwritable(const std::string& path, const std::vector<Input>& inputs) {
  struct stat st;
  if (::lstat(path.c_str(), &st) != 0) return errno == ENOENT ? "" : std::strerror(errno);
  if (S_ISLNK(st.st_mode)) return "is a symbolic link";
  if (!S_ISREG(st.st_mode)) return "is not a regular file";
  for (const Input& in : inputs)
    if (in.id == FileId{st.st_dev, st.st_ino})
      return "is " + in.what + (in.path == path ? "" : " (" + in.path + ")");
  return "";
}

bool WriteFileAtomic(const std::string& path, const std::string& data, std::string* err,
                     bool sync) {
  return WriteFileAtomic(
      path, [&](const FileSink& put) { return put(data.data(), data.size()); }, err, sync);
}

bool WriteFileAtomic(const std::string& path, const std::function<bool(const FileSink&)>& body,
                     std::string* err, bool sync) {
  const std::string why = Unwritable(path, {});
  if (!why.empty()) {
    *err = path + ": " + why + "; not replaced";
    return false;
  }
  std::string tmp = path + ".XXXXXX";
  const int fd = ::mkostemp(&tmp[0], O_CLOEXEC);
  if (fd < 0) {
    *err = path + ": cannot create a file in " + DirName(path) + ": " + std::strerror(errno);
    return false;
  }
  const FileSink put = [fd](const char* data, size_t size) { return WriteAll(fd, data, size); };
  bool ok = ::fchmod(fd, CreateMode()) == 0 && body(put) && (!sync || ::fsync(fd) == 0);
  const int e = errno;
  ok = ::close(fd) == 0 && ok;
  if (ok && ::rename(tmp.c_str(), path.c_str()) == 0) return true;
  *err = Errno(path);
  if (!ok) *err = path + ": " + std::strerror(e);
  ::unlink(tmp.c_str());
  return false;
}

std::string DirName(const std::string& path) {
  const size_t slash = path.rfind('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

Staging::~Staging() { Discard(); }

bool Staging::Open(const std::string& dir, std::string* err) {
  dir_ = dir;
  std::string t = dir + "/.radiosity-XXXXXX";
  if (!::mkdtemp(&t[0])) {
    *err = dir + ": cannot create a directory in it: " + std::strerror(errno);
    return false;
  }
  stage_ = t;
  return true;
}

bool Staging::Commit(const std::vector<Input>& inputs,
                     const std::function<bool(const std::string&)>& ours, std::string* err) {
  std::set<std::string> names;
  if (DIR* d = ::opendir(stage_.c_str())) {
    while (dirent* e = ::readdir(d))
      if (e->d_name[0] != '.') names.insert(e->d_name);
    ::closedir(d);
  }
  for (const std::string& n : names) {
    const std::string why = Unwritable(dir_ + "/" + n, inputs);
    if (!why.empty()) {
      *err = dir_ + "/" + n + ": " + why + "; no results moved there (they are in " + stage_ + ")";
      stage_.clear();  // kept for the user
      return false;
    }
  }
  // Held, not ignored: a second Ctrl-C still ends the program, once the
  // directory holds one run's outputs.
  sigset_t hold, old;
  sigemptyset(&hold);
  for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&hold, s);
  ::sigprocmask(SIG_BLOCK, &hold, &old);
  bool ok = true;
  for (const std::string& n : names) {
    if (::rename((stage_ + "/" + n).c_str(), (dir_ + "/" + n).c_str()) != 0) {
      *err = Errno(dir_ + "/" + n);
      ok = false;
      break;
    }
  }
  if (ok) {
    if (DIR* d = ::opendir(dir_.c_str())) {
      std::vector<std::string> stale;
      while (dirent* e = ::readdir(d))
        if (!names.count(e->d_name) && ours(e->d_name)) stale.push_back(e->d_name);
      ::closedir(d);
      for (const std::string& n : stale)
        if (Unwritable(dir_ + "/" + n, {}).empty()) ::unlink((dir_ + "/" + n).c_str());
    }
  }
  Discard();
  ::sigprocmask(SIG_SETMASK, &old, nullptr);
  return ok;
}

void Staging::Discard() {
  if (stage_.empty()) return;
  if (DIR* d = ::opendir(stage_.c_str())) {
    while (dirent* e = ::readdir(d))
      if (e->d_name[0] != '.') ::unlink((stage_ + "/" + e->d_name).c_str());
    ::closedir(d);
  }
  ::rmdir(stage_.c_str());
  stage_.clear();
}
