#include "limited_load.h"

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <typeinfo>

#include "gpucol/mesh_error.h"
#include "gpucol/triangle_mesh.h"

#if defined(__SANITIZE_ADDRESS__)
#define GPUCOL_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define GPUCOL_TEST_ASAN 1
#endif
#endif

namespace gpucol::test {

namespace {

/// The process's address space in bytes (the first field of /proc/self/statm, in pages).
std::size_t addressSpace() {
  std::ifstream statm("/proc/self/statm");
  std::size_t pages = 0;
  statm >> pages;
  return pages * std::size_t(sysconf(_SC_PAGESIZE));
}

void writeAll(int fd, const std::string& bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    done += std::size_t(n);
  }
}

template <typename T>
void append(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof value);
}

template <typename T>
T take(const std::string& in, std::size_t& at) {
  T value{};
  if (at + sizeof value <= in.size()) std::memcpy(&value, in.data() + at, sizeof value);
  at += sizeof value;
  return value;
}

}  // namespace

LimitedLoad loadWithinLimits(const std::string& path, std::size_t memoryBytes, unsigned seconds) {
  LimitedLoad result;
  int fds[2];
  if (pipe(fds) != 0) {
    result.message = std::string("pipe failed: ") + std::strerror(errno);
    return result;
  }
  std::fflush(nullptr);
  const pid_t child = fork();
  if (child == 0) {
    close(fds[0]);
#ifndef GPUCOL_TEST_ASAN
    const rlimit limit{addressSpace() + memoryBytes, addressSpace() + memoryBytes};
    setrlimit(RLIMIT_AS, &limit);
#else
    (void)memoryBytes;
#endif
    alarm(seconds);
    std::string out;
    try {
      const TriangleMesh mesh = loadMesh(path);
      out = "L";
      append(out, std::uint64_t(mesh.positions().size()));
      append(out, std::uint64_t(mesh.indices().size()));
      append(out, char(mesh.report().closed));
      out.append(reinterpret_cast<const char*>(mesh.positions().data()), 4 * mesh.positions().size());
      out.append(reinterpret_cast<const char*>(mesh.indices().data()), 4 * mesh.indices().size());
    } catch (const MeshError& e) {
      out = std::string("E") + e.what();
    } catch (const std::exception& e) {
      out = std::string("X") + typeid(e).name() + ": " + e.what();
    }
    writeAll(fds[1], out);
    _exit(0);
  }
  close(fds[1]);
  std::string in;
  char buffer[65536];
  for (;;) {
    const ssize_t n = read(fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    in.append(buffer, std::size_t(n));
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || in.empty()) {
    result.outcome = LimitedLoad::Outcome::kKilled;
    result.message = WIFSIGNALED(status)
                         ? std::string("killed by signal ") + strsignal(WTERMSIG(status)) +
                               (WTERMSIG(status) == SIGALRM ? " (time limit)" : "")
                         : "the child exited with status " + std::to_string(WEXITSTATUS(status));
    return result;
  }
  if (in[0] == 'E' || in[0] == 'X') {
    result.outcome = in[0] == 'E' ? LimitedLoad::Outcome::kMeshError : LimitedLoad::Outcome::kOtherException;
    result.message = in.substr(1);
    return result;
  }
  std::size_t at = 1;
  const auto floats = take<std::uint64_t>(in, at), indices = take<std::uint64_t>(in, at);
  result.closed = take<char>(in, at) != 0;
  if (in.size() != at + 4 * (floats + indices)) {
    result.message = "a truncated answer from the child";
    return result;
  }
  result.xyz.resize(std::size_t(floats));
  result.indices.resize(std::size_t(indices));
  std::memcpy(result.xyz.data(), in.data() + at, 4 * std::size_t(floats));
  std::memcpy(result.indices.data(), in.data() + at + 4 * floats, 4 * std::size_t(indices));
  result.outcome = LimitedLoad::Outcome::kLoaded;
  return result;
}

}  // namespace gpucol::test
