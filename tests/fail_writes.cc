// LD_PRELOAD shim for tests: write(2) and writev(2) to a regular file whose path contains
// $JOINTLAB_FAIL_WRITES_TO fail with ENOSPC, as they do on a full disk; so do sendfile(2) and
// copy_file_range(2), how std::filesystem::copy fills a file, to a path containing
// $JOINTLAB_FAIL_COPIES_TO. Lets a test run
// the unmodified jointlab command into a "full disk" without a small filesystem.
#include <dlfcn.h>
#include <sys/sendfile.h>
#include <sys/stat.h>
#include <sys/uio.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <string>

namespace {

bool fails(int fd, const char* variable = "JOINTLAB_FAIL_WRITES_TO") {
  const char* pattern = std::getenv(variable);
  if (!pattern || !*pattern) return false;
  struct stat st {};
  if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) return false;
  char link[64], target[PATH_MAX];
  std::snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
  const ssize_t n = readlink(link, target, sizeof target - 1);
  if (n <= 0) return false;
  target[n] = '\0';
  return std::strstr(target, pattern) != nullptr;
}

}  // namespace

extern "C" ssize_t write(int fd, const void* buf, size_t count) {
  using Fn = ssize_t (*)(int, const void*, size_t);
  static const Fn real = reinterpret_cast<Fn>(dlsym(RTLD_NEXT, "write"));
  if (fails(fd)) {
    errno = ENOSPC;
    return -1;
  }
  return real(fd, buf, count);
}

extern "C" ssize_t writev(int fd, const struct iovec* iov, int iovcnt) {
  using Fn = ssize_t (*)(int, const struct iovec*, int);
  static const Fn real = reinterpret_cast<Fn>(dlsym(RTLD_NEXT, "writev"));
  if (fails(fd)) {
    errno = ENOSPC;
    return -1;
  }
  return real(fd, iov, iovcnt);
}

extern "C" ssize_t sendfile(int out_fd, int in_fd, off_t* offset, size_t count) {
  using Fn = ssize_t (*)(int, int, off_t*, size_t);
  static const Fn real = reinterpret_cast<Fn>(dlsym(RTLD_NEXT, "sendfile"));
  if (fails(out_fd, "JOINTLAB_FAIL_COPIES_TO")) {
    errno = ENOSPC;
    return -1;
  }
  return real(out_fd, in_fd, offset, count);
}

extern "C" ssize_t copy_file_range(int in_fd, off_t* in_off, int out_fd, off_t* out_off, size_t len,
                                   unsigned flags) {
  using Fn = ssize_t (*)(int, off_t*, int, off_t*, size_t, unsigned);
  static const Fn real = reinterpret_cast<Fn>(dlsym(RTLD_NEXT, "copy_file_range"));
  if (fails(out_fd, "JOINTLAB_FAIL_COPIES_TO")) {
    errno = ENOSPC;
    return -1;
  }
  return real(in_fd, in_off, out_fd, out_off, len, flags);
}
