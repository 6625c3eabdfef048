// The transport of retarget-infer --stream --listen PORT: one loopback TCP client (127.0.0.1
// only: frames of a person's face are not for the network) as a buffered std::iostream, and the
// listening socket that accepts it. FdStream also wraps pipes (the tests' slow, live input).
#pragma once

#include <iostream>
#include <memory>
#include <streambuf>
#include <string>
#include <vector>

namespace retarget {

// A file descriptor (socket or pipe) as a std::streambuf: reads block until bytes arrive (0 bytes:
// end of input, also when the peer closed mid-line), writes go out on sync() (std::flush) and
// when the buffer is full. Writes never raise SIGPIPE (a client gone is a failed write: the
// stream's badbit).
class FdStreamBuf : public std::streambuf {
 public:
  // fd: open for reading and/or writing; own: close it in the destructor.
  explicit FdStreamBuf(int fd, bool own = true);
  ~FdStreamBuf() override;
  FdStreamBuf(const FdStreamBuf&) = delete;
  FdStreamBuf& operator=(const FdStreamBuf&) = delete;
  int fd() const { return fd_; }

 protected:
  int_type underflow() override;
  int_type overflow(int_type c) override;
  int sync() override;

 private:
  bool send_all(const char* data, size_t size);
  int fd_;
  bool own_;
  std::vector<char> in_, out_;
};

// FdStreamBuf as an iostream.
class FdStream : public std::iostream {
 public:
  explicit FdStream(int fd, bool own = true);
  ~FdStream() override;
  int fd() const { return buffer_.fd(); }
  // Stops reading (a socket: shutdown of the read side, so a blocked read returns end of input).
  void shutdown_read();
  // Flushes, then tells the peer no more bytes come (a socket: shutdown of the write side, the
  // peer reads end of input; the connection stays open for reading).
  void shutdown_write();

 private:
  FdStreamBuf buffer_;
};

class LoopbackListener {
 public:
  // Listens on 127.0.0.1:port (0: a free port the system picks; port() tells which). Throws
  // retarget::Error("--listen", ...) when the port cannot be bound (taken, or below 1024
  // without the right).
  explicit LoopbackListener(int port);
  ~LoopbackListener();
  LoopbackListener(const LoopbackListener&) = delete;
  LoopbackListener& operator=(const LoopbackListener&) = delete;
  int port() const { return port_; }

  // Waits for one client and returns its connection. Throws retarget::Error("--listen", ...) on failure.
  std::unique_ptr<FdStream> accept();

 private:
  int fd_ = -1;
  int port_ = 0;
};

// A client of LoopbackListener (tests, benchmarks): the connection to 127.0.0.1:port. Throws
// retarget::Error when it cannot connect.
std::unique_ptr<FdStream> connect_loopback(int port);

}  // namespace retarget
