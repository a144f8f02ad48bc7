#include "mesh/mesh_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "gpucol/mesh_error.h"

namespace gpucol {

namespace {

/// What a file that is not regular is, for the message.
const char* kindOf(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

/// Closes the descriptor on every way out.
struct Descriptor {
  int fd;
  ~Descriptor() { ::close(fd); }
};

}  // namespace

void checkMeshFile(const std::string& path) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0)
    throw MeshError(path + ": cannot open mesh file: " + std::strerror(errno));
  if (!S_ISREG(info.st_mode))
    throw MeshError(path + ": cannot read mesh file: it is " + kindOf(info.st_mode));
  if (info.st_size == 0) throw MeshError(path + ": the mesh file is empty");
}

std::string readMeshFile(const std::string& path) {
  checkMeshFile(path);
  struct stat info {};
  // O_NONBLOCK: should the path have become a FIFO since the stat, the open returns at once and fstat refuses
  // it.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) throw MeshError(path + ": cannot open mesh file: " + std::strerror(errno));
  const Descriptor held{fd};
  if (::fstat(fd, &info) != 0) throw MeshError(path + ": cannot read mesh file: " + std::strerror(errno));
  if (!S_ISREG(info.st_mode))
    throw MeshError(path + ": cannot read mesh file: it is " + kindOf(info.st_mode));
  if (info.st_size == 0) throw MeshError(path + ": the mesh file is empty");

  std::string bytes(std::size_t(info.st_size), '\0');
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t got = ::read(fd, &bytes[done], bytes.size() - done);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) throw MeshError(path + ": cannot read mesh file: " + std::strerror(errno));
    if (got == 0) throw MeshError(path + ": cannot read mesh file: it became shorter while it was read");
    done += std::size_t(got);
  }
  // A file that grew since the stat would be read only in part: refused, rather than loaded cut.
  char extra = 0;
  ssize_t more = 0;
  do {
    more = ::read(fd, &extra, 1);
  } while (more < 0 && errno == EINTR);
  if (more != 0) throw MeshError(path + ": cannot read mesh file: it grew while it was read");
  return bytes;
}

void throwMalformed(const std::string& path, const char* format, const std::string& what) {
  throw MeshError(path + ": malformed " + format + " file: " + what);
}

}  // namespace gpucol
