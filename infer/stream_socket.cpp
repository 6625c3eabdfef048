#include "infer/stream_socket.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "core/error.h"

namespace retarget {

namespace stream_socket_detail {

constexpr size_t kBufferBytes = 1 << 16;

std::string system_error(const std::string& what) { return what + ": " + std::strerror(errno); }

sockaddr_in loopback_address(int port) {
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  return address;
}

}  // namespace stream_socket_detail

FdStreamBuf::FdStreamBuf(int fd, bool own)
    : fd_(fd), own_(own), in_(stream_socket_detail::kBufferBytes), out_(stream_socket_detail::kBufferBytes) {
  setg(in_.data(), in_.data(), in_.data());
  setp(out_.data(), out_.data() + out_.size());
}

FdStreamBuf::~FdStreamBuf() {
  sync();
  if (own_ && fd_ >= 0) ::close(fd_);
}

FdStreamBuf::int_type FdStreamBuf::underflow() {
  if (gptr() < egptr()) return traits_type::to_int_type(*gptr());
  while (true) {
    const ssize_t n = ::read(fd_, in_.data(), in_.size());
    if (n > 0) {
      setg(in_.data(), in_.data(), in_.data() + n);
      return traits_type::to_int_type(*gptr());
    }
    if (n < 0 && errno == EINTR) continue;
    return traits_type::eof();  // the end, a reset connection or a read side shut down
  }
}

bool FdStreamBuf::send_all(const char* data, size_t size) {
  while (size > 0) {
    ssize_t n = ::send(fd_, data, size, MSG_NOSIGNAL);
    if (n < 0 && errno == ENOTSOCK) n = ::write(fd_, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data += n;
    size -= static_cast<size_t>(n);
  }
  return true;
}

FdStreamBuf::int_type FdStreamBuf::overflow(int_type c) {
  if (sync() != 0) return traits_type::eof();
  if (!traits_type::eq_int_type(c, traits_type::eof())) {
    *pptr() = traits_type::to_char_type(c);
    pbump(1);
  }
  return traits_type::not_eof(c);
}

int FdStreamBuf::sync() {
  const size_t size = static_cast<size_t>(pptr() - pbase());
  if (size == 0) return 0;
  const bool ok = send_all(pbase(), size);
  setp(out_.data(), out_.data() + out_.size());
  return ok ? 0 : -1;
}

FdStream::FdStream(int fd, bool own) : std::iostream(nullptr), buffer_(fd, own) { rdbuf(&buffer_); }

FdStream::~FdStream() { flush(); }

void FdStream::shutdown_read() { ::shutdown(buffer_.fd(), SHUT_RD); }

void FdStream::shutdown_write() {
  flush();
  ::shutdown(buffer_.fd(), SHUT_WR);
}

LoopbackListener::LoopbackListener(int port) {
  using namespace stream_socket_detail;
  fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw Error("--listen", system_error("cannot open a socket"));
  const int yes = 1;
  ::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  sockaddr_in address = loopback_address(port);
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 || ::listen(fd_, 1) != 0) {
    const std::string message = system_error("cannot listen on 127.0.0.1:" + std::to_string(port));
    ::close(fd_);
    throw Error("--listen", message);
  }
  socklen_t size = sizeof address;
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&address), &size);
  port_ = ntohs(address.sin_port);
}

LoopbackListener::~LoopbackListener() {
  if (fd_ >= 0) ::close(fd_);
}

std::unique_ptr<FdStream> LoopbackListener::accept() {
  while (true) {
    const int client = ::accept4(fd_, nullptr, nullptr, SOCK_CLOEXEC);
    if (client >= 0) return std::make_unique<FdStream>(client);
    if (errno == EINTR || errno == ECONNABORTED) continue;
    throw Error("--listen", stream_socket_detail::system_error("accepting a client failed"));
  }
}

std::unique_ptr<FdStream> connect_loopback(int port) {
  using namespace stream_socket_detail;
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw Error("127.0.0.1:" + std::to_string(port), system_error("cannot open a socket"));
  sockaddr_in address = loopback_address(port);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) {
    const std::string message = system_error("cannot connect");
    ::close(fd);
    throw Error("127.0.0.1:" + std::to_string(port), message);
  }
  return std::make_unique<FdStream>(fd);
}

}  // namespace retarget
