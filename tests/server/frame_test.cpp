#include "frame.h"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <string>
#include <thread>

#include "rdmesh/internal/worker.pb.h"

namespace rdmesh::server {
namespace {

namespace wire = ::rdmesh::internal;

class FrameTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_EQ(socketpair(AF_UNIX, SOCK_STREAM, 0, fds_), 0); }
  void TearDown() override {
    for (int fd : fds_) {
      if (fd >= 0) close(fd);
    }
  }
  void CloseWriter() {
    close(fds_[0]);
    fds_[0] = -1;
  }
  int fds_[2] = {-1, -1};
};

TEST_F(FrameTest, MessagesArriveWholeAndInOrder) {
  // A large message (several socket buffers) is written by one thread and read by another.
  wire::FromWorker big;
  auto* face = big.mutable_event()->mutable_face();
  face->set_face_id(7);
  for (int i = 0; i < 300000; ++i) face->add_xyz(i * 0.5);
  wire::FromWorker small;
  small.mutable_done()->set_code(3);
  small.mutable_done()->set_message("cannot read");
  std::thread writer([&] {
    EXPECT_TRUE(WriteFrame(fds_[0], big));
    EXPECT_TRUE(WriteFrame(fds_[0], small));
  });
  wire::FromWorker got;
  ASSERT_EQ(ReadFrame(fds_[1], &got, 5000), FrameRead::kMessage);
  EXPECT_EQ(got.event().face().face_id(), 7);
  ASSERT_EQ(got.event().face().xyz_size(), 300000);
  EXPECT_EQ(got.event().face().xyz(299999), 299999 * 0.5);
  ASSERT_EQ(ReadFrame(fds_[1], &got, 5000), FrameRead::kMessage);
  EXPECT_EQ(got.done().code(), 3);
  EXPECT_EQ(got.done().message(), "cannot read");
  writer.join();
}

TEST_F(FrameTest, TimeoutWhenNothingArrives) {
  wire::FromWorker got;
  EXPECT_EQ(ReadFrame(fds_[1], &got, 30), FrameRead::kTimeout);
}

TEST_F(FrameTest, ClosedWhenThePeerEndsMidFrame) {
  const unsigned char header[4] = {100, 0, 0, 0};  // announces 100 bytes, sends 3
  ASSERT_EQ(write(fds_[0], header, 4), 4);
  ASSERT_EQ(write(fds_[0], "abc", 3), 3);
  CloseWriter();
  wire::FromWorker got;
  EXPECT_EQ(ReadFrame(fds_[1], &got, 1000), FrameRead::kClosed);
}

TEST_F(FrameTest, ClosedAtEndOfFile) {
  CloseWriter();
  wire::FromWorker got;
  EXPECT_EQ(ReadFrame(fds_[1], &got, 1000), FrameRead::kClosed);
}

TEST_F(FrameTest, CorruptWhenTheLengthIsAbsurdOrTheBytesDoNotParse) {
  const unsigned char huge[4] = {0xff, 0xff, 0xff, 0x7f};
  ASSERT_EQ(write(fds_[0], huge, 4), 4);
  wire::FromWorker got;
  EXPECT_EQ(ReadFrame(fds_[1], &got, 1000), FrameRead::kCorrupt);

  const unsigned char header[4] = {2, 0, 0, 0};
  ASSERT_EQ(write(fds_[0], header, 4), 4);
  ASSERT_EQ(write(fds_[0], "\xff\xff", 2), 2);  // an invalid tag
  EXPECT_EQ(ReadFrame(fds_[1], &got, 1000), FrameRead::kCorrupt);
}

TEST_F(FrameTest, WriteToAClosedPeerFailsWithoutSigpipe) {
  close(fds_[1]);
  fds_[1] = -1;
  wire::ToWorker call;
  call.set_request_id("r");
  call.mutable_cancel();
  EXPECT_FALSE(WriteFrame(fds_[0], call));  // SIGPIPE would end the test binary
}

}  // namespace
}  // namespace rdmesh::server
