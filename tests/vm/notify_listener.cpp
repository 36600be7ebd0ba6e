// systemd's side of the sd_notify protocol, for the VM bench (which boots busybox, not systemd):
// binds a datagram socket at the path given, prints every message it receives on one line
// ("NOTIFY <message with newlines as |>"), and stops after the given number of seconds.
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: notify_listener SOCKET_PATH SECONDS\n");
    return 2;
  }
  const int fd = ::socket(AF_UNIX, SOCK_DGRAM, 0);
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  std::strncpy(a.sun_path, argv[1], sizeof a.sun_path - 1);
  ::unlink(argv[1]);
  if (fd < 0 || ::bind(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    std::perror("notify_listener: bind");
    return 1;
  }
  timespec start{};
  ::clock_gettime(CLOCK_MONOTONIC, &start);
  const double seconds = std::atof(argv[2]);
  for (;;) {
    timespec now{};
    ::clock_gettime(CLOCK_MONOTONIC, &now);
    const double elapsed = static_cast<double>(now.tv_sec - start.tv_sec) +
                           static_cast<double>(now.tv_nsec - start.tv_nsec) * 1e-9;
    if (elapsed >= seconds) break;
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 200) <= 0) continue;
    char buf[1024];
    const ssize_t n = ::recv(fd, buf, sizeof buf - 1, 0);
    if (n <= 0) continue;
    for (ssize_t i = 0; i < n; ++i)
      if (buf[i] == '\n') buf[i] = '|';
    buf[n] = '\0';
    std::printf("NOTIFY %.2f %s\n", elapsed, buf);
    std::fflush(stdout);
  }
  ::unlink(argv[1]);
  return 0;
}
