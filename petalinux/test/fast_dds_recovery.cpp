// Copyright 2026 py_vision contributors
//
// Licensed under the Apache License, Version 2.0 (the "License");
// you may not use this file except in compliance with the License.
// You may obtain a copy of the License at
//
//     http://www.apache.org/licenses/LICENSE-2.0
//
// Unless required by applicable law or agreed to in writing, software
// distributed under the License is distributed on an "AS IS" BASIS,
// WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
// See the License for the specific language governing permissions and
// limitations under the License.

// Fast DDS 2.6.0's shared-memory transport recovering from a reader that crashed in the middle
// of a message, with the board image's patches: test_fast_dds_patches.py compiles this against
// Fast DDS' own source files (fixtures/fast-dds-2.6.0, the patches of the bbappend applied) and
// Debian's Boost headers, and runs it.
//
// Usage: fast_dds_recovery DOMAIN_NAME   (at most 16 characters; its files go to /dev/shm)
//
// What happens, in Fast DDS' own classes:
// - a reader process opens a port (ReadExclusive, as a participant's port is), takes the one
//   message the writer pushes and exits without finishing it, as a crashed participant does:
//   the port still marks its listener as processing that buffer;
// - the writer (this process) then cannot allocate its segment's only buffer again: the dead
//   reader still holds it;
// - the writer calls SharedMemManager::Port::recover_blocked_processing(), what Fast DDS runs
//   when it regenerates a port whose reader died, and allocates the buffer again.
//
// Every lock of an interprocess mutex is a pthread_mutex_timedlock: Fast DDS builds Boost with
// BOOST_INTERPROCESS_ENABLE_TIMEOUT_WHEN_LOCKING (1 s, its boostconfig.hpp), so a lock that
// waits longer throws, and Fast DDS swallows that. The link wraps pthread_mutex_timedlock
// (-Wl,--wrap=pthread_mutex_timedlock): a lock of a mutex by the very thread that holds it is
// reported, then goes on to time out as in Fast DDS. After SELF_LOCKS of them the program
// stops: the recovery would go on for ever, one second a pass.
//
// Exit status: 0 recovered; 3 a thread locked a mutex it already held (the self-deadlock);
// 1 anything else (the message says what).

#include <pthread.h>
#include <signal.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <memory>
#include <string>
#include <thread>

// Fast DDS' logging is its library's (fastdds/dds/log/Log.hpp), which these headers expect the
// file that includes them to have included: here its three macros print to stderr.
namespace eprosima {
namespace fastdds {
namespace dds {
class Log;
}  // namespace dds
}  // namespace fastdds
}  // namespace eprosima
#define logError(cat, msg) (std::cerr << "[" #cat " error] " << msg << std::endl)
#define logWarning(cat, msg) (std::cerr << "[" #cat " warning] " << msg << std::endl)
#define logInfo(cat, msg) do {} while (0)

#include <rtps/transport/shared_mem/SharedMemManager.hpp>

using eprosima::fastdds::rtps::SharedMemGlobal;
using eprosima::fastdds::rtps::SharedMemManager;

namespace
{

const uint32_t PORT_ID = 7411;
const uint32_t PORT_CAPACITY = 16;
const uint32_t HEALTHY_CHECK_MS = 1000;
const uint32_t PAYLOAD = 64;
// Locks of a mutex by its holder before the program gives up on the recovery.
const int SELF_LOCKS = 3;

int self_locks = 0;
const char * phase = "start";
bool reader_reaped = false;

}  // namespace

extern "C" int __real_pthread_mutex_timedlock(pthread_mutex_t * mutex, const timespec * deadline);

// Every timed lock of the program comes here first (the link's --wrap).
extern "C" int __wrap_pthread_mutex_timedlock(pthread_mutex_t * mutex, const timespec * deadline)
{
  const int self = static_cast<int>(syscall(SYS_gettid));
  // glibc keeps the holder's thread id in the mutex (the high bits are robust-mutex flags).
  if ((mutex->__data.__owner & 0x3fffffff) != self) {
    return __real_pthread_mutex_timedlock(mutex, deadline);
  }
  ++self_locks;
  std::cout << "self-lock " << self_locks << " (" << phase << "): thread " << self <<
    " locks the interprocess mutex at " << static_cast<void *>(mutex) <<
    ", which it holds already; Fast DDS waits 1 s for it, gives up and goes on" << std::endl;
  const int result = __real_pthread_mutex_timedlock(mutex, deadline);
  if (self_locks >= SELF_LOCKS) {
    std::cout << "SELF-DEADLOCK: " << phase << " locked a mutex its own thread holds " <<
      self_locks << " times (each lock returned " << (result == ETIMEDOUT ? "ETIMEDOUT" :
      std::to_string(result)) << " after its timeout): it does not end" << std::endl;
    std::_Exit(3);
  }
  return result;
}

namespace
{

int fail(const std::string & what)
{
  std::cout << "FAILED: " << what << std::endl;
  return 1;
}

void send_byte(int fd, char byte)
{
  if (write(fd, &byte, 1) != 1) {
    std::_Exit(1);
  }
}

char receive_byte(int fd)
{
  char byte = 0;
  return read(fd, &byte, 1) == 1 ? byte : 0;
}

// The reader: take one message, tell the writer, and exit as a crash would (no destructor runs).
[[noreturn]] void crashing_reader(const std::string & domain, int to_writer)
{
  try {
    auto manager = SharedMemManager::create(domain);
    auto port = manager->open_port(PORT_ID, PORT_CAPACITY, HEALTHY_CHECK_MS,
        SharedMemGlobal::Port::OpenMode::ReadExclusive);
    auto listener = port->create_listener();
    send_byte(to_writer, 'R');
    auto buffer = listener->pop();
    send_byte(to_writer, buffer ? 'P' : 'E');
    std::_Exit(0);  // here, holding the buffer: no destructor of Fast DDS' objects runs
  } catch (const std::exception & error) {
    std::cout << "reader: " << error.what() << std::endl;
    send_byte(to_writer, 'E');
  }
  std::_Exit(0);
}

bool can_allocate(SharedMemManager::Segment & segment)
{
  try {
    segment.alloc_buffer(PAYLOAD, std::chrono::steady_clock::now());
    return true;
  } catch (const std::exception & error) {
    std::cout << "writer: allocating the segment's buffer: " << error.what() << std::endl;
    return false;
  }
}

int writer(const std::string & domain, pid_t reader, int from_reader)
{
  if (receive_byte(from_reader) != 'R') {
    return fail("the reader did not open its port");
  }
  auto manager = SharedMemManager::create(domain);
  // One buffer: a buffer the dead reader still holds cannot be replaced by another.
  auto segment = manager->create_segment(PAYLOAD, 1);
  auto port = manager->open_port(PORT_ID, PORT_CAPACITY, HEALTHY_CHECK_MS,
      SharedMemGlobal::Port::OpenMode::Write);
  {
    auto buffer = segment->alloc_buffer(PAYLOAD, std::chrono::steady_clock::now());
    std::memset(buffer->data(), 0x5a, PAYLOAD);
    if (!port->try_push(buffer)) {
      return fail("the writer could not push its message to the reader's port");
    }
  }
  if (receive_byte(from_reader) != 'P') {
    return fail("the reader did not take the message");
  }
  int status = 0;
  if (waitpid(reader, &status, 0) != reader || !WIFEXITED(status)) {
    return fail("the reader did not exit");
  }
  reader_reaped = true;
  std::cout << "writer: the reader took the message and exited without finishing it" <<
    std::endl;
  if (can_allocate(*segment)) {
    return fail("the writer could allocate its only buffer while the dead reader held it");
  }
  std::cout << "writer: its only buffer is held by the dead reader" << std::endl;

  phase = "recover_blocked_processing()";
  const auto start = std::chrono::steady_clock::now();
  port->recover_blocked_processing();
  const auto took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start);
  phase = "after the recovery";
  std::cout << "writer: recover_blocked_processing() returned after " << took.count() <<
    " s" << std::endl;
  if (!can_allocate(*segment)) {
    return fail("after the recovery the writer still cannot allocate its buffer");
  }
  std::cout << "writer: the buffer is free again: RECOVERED" << std::endl;
  return 0;
}

}  // namespace

int main(int argc, char ** argv)
{
  if (argc != 2) {
    std::cerr << "usage: fast_dds_recovery DOMAIN_NAME" << std::endl;
    return 2;
  }
  const std::string domain = argv[1];
  int pipe_fds[2];
  if (pipe(pipe_fds) != 0) {
    return fail("pipe");
  }
  std::cout.setf(std::ios::unitbuf);
  // Before any thread or shared memory of Fast DDS exists in this process.
  const pid_t reader = fork();
  if (reader < 0) {
    return fail("fork");
  }
  if (reader == 0) {
    close(pipe_fds[0]);
    crashing_reader(domain, pipe_fds[1]);
  }
  close(pipe_fds[1]);
  int status;
  try {
    status = writer(domain, reader, pipe_fds[0]);
  } catch (const std::exception & error) {
    status = fail(std::string("writer: ") + error.what());
  }
  if (!reader_reaped) {  // a failure before the reader exited: it may wait for a message still
    kill(reader, SIGKILL);
    waitpid(reader, nullptr, 0);
  }
  return status;
}
