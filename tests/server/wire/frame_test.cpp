#include "wire/frame.h"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <memory>
#include <string>
#include <thread>

#include "rdmesh/internal/worker.pb.h"

namespace rdmesh::server {
namespace {

namespace wire = ::rdmesh::internal;

// Every reading test runs twice: with ReadFrame (false) and with a FrameReader (true).
class FrameTest : public ::testing::TestWithParam<bool> {
 protected:
  void SetUp() override {
    ASSERT_EQ(socketpair(AF_UNIX, SOCK_STREAM, 0, fds_), 0);
    if (GetParam()) reader_ = std::make_unique<FrameReader>(fds_[1]);
  }
  void TearDown() override {
    for (int fd : fds_) {
      if (fd >= 0) close(fd);
    }
  }
  void CloseWriter() {
    close(fds_[0]);
    fds_[0] = -1;
  }
  FrameRead Read(wire::FromWorker* message, int timeout_ms) {
    return reader_ ? reader_->Read(message, timeout_ms) : ReadFrame(fds_[1], message, timeout_ms);
  }
  int fds_[2] = {-1, -1};
  std::unique_ptr<FrameReader> reader_;
};

INSTANTIATE_TEST_SUITE_P(Readers, FrameTest, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? "Buffered" : "Direct";
                         });

TEST_P(FrameTest, MessagesArriveWholeAndInOrder) {
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
  ASSERT_EQ(Read(&got, 5000), FrameRead::kMessage);
  EXPECT_EQ(got.event().face().face_id(), 7);
  ASSERT_EQ(got.event().face().xyz_size(), 300000);
  EXPECT_EQ(got.event().face().xyz(299999), 299999 * 0.5);
  ASSERT_EQ(Read(&got, 5000), FrameRead::kMessage);
  EXPECT_EQ(got.done().code(), 3);
  EXPECT_EQ(got.done().message(), "cannot read");
  writer.join();
}

// Many small frames written at once: a FrameReader takes several from one read(), and a frame
// split across reads still arrives whole.
TEST_P(FrameTest, ManySmallFramesInOrder) {
  constexpr int kFrames = 5000;
  std::thread writer([&] {
    for (int i = 0; i < kFrames; ++i) {
      wire::FromWorker event;
      event.mutable_event()->mutable_face()->set_face_id(i);
      for (int k = 0; k < i % 50; ++k) event.mutable_event()->mutable_face()->add_xyz(k);
      ASSERT_TRUE(WriteFrame(fds_[0], event));
    }
  });
  wire::FromWorker got;
  for (int i = 0; i < kFrames; ++i) {
    ASSERT_EQ(Read(&got, 5000), FrameRead::kMessage) << i;
    ASSERT_EQ(got.event().face().face_id(), i);
    ASSERT_EQ(got.event().face().xyz_size(), i % 50);
  }
  writer.join();
  EXPECT_EQ(Read(&got, 30), FrameRead::kTimeout);
}

TEST_P(FrameTest, TimeoutWhenNothingArrives) {
  wire::FromWorker got;
  EXPECT_EQ(Read(&got, 30), FrameRead::kTimeout);
}

TEST_P(FrameTest, ClosedWhenThePeerEndsMidFrame) {
  const unsigned char header[4] = {100, 0, 0, 0};  // announces 100 bytes, sends 3
  ASSERT_EQ(write(fds_[0], header, 4), 4);
  ASSERT_EQ(write(fds_[0], "abc", 3), 3);
  CloseWriter();
  wire::FromWorker got;
  EXPECT_EQ(Read(&got, 1000), FrameRead::kClosed);
}

TEST_P(FrameTest, ClosedAtEndOfFile) {
  CloseWriter();
  wire::FromWorker got;
  EXPECT_EQ(Read(&got, 1000), FrameRead::kClosed);
}

TEST_P(FrameTest, CorruptWhenTheLengthIsAbsurdOrTheBytesDoNotParse) {
  const unsigned char huge[4] = {0xff, 0xff, 0xff, 0x7f};
  ASSERT_EQ(write(fds_[0], huge, 4), 4);
  wire::FromWorker got;
  EXPECT_EQ(Read(&got, 1000), FrameRead::kCorrupt);

  const unsigned char header[4] = {2, 0, 0, 0};
  ASSERT_EQ(write(fds_[0], header, 4), 4);
  ASSERT_EQ(write(fds_[0], "\xff\xff", 2), 2);  // an invalid tag
  EXPECT_EQ(Read(&got, 1000), FrameRead::kCorrupt);
}

TEST_P(FrameTest, WriteToAClosedPeerFailsWithoutSigpipe) {
  close(fds_[1]);
  fds_[1] = -1;
  wire::ToWorker call;
  call.set_request_id("r");
  call.mutable_cancel();
  EXPECT_FALSE(WriteFrame(fds_[0], call));  // SIGPIPE would end the test binary
}

}  // namespace
}  // namespace rdmesh::server
