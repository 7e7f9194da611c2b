#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "plc/modbus_request.hpp"
#include "plc/register_map.hpp"

namespace pipeloc {
namespace {

TEST(Encoding, FloatInEveryWordOrder) {
  std::uint16_t r[2];
  // DESIGN.md's reference value: 123456.0f is 0x47F12000.
  encode_float(123456.0f, WordOrder::abcd, r);
  EXPECT_EQ(r[0], 0x47F1);
  EXPECT_EQ(r[1], 0x2000);
  encode_float(123456.0f, WordOrder::cdab, r);
  EXPECT_EQ(r[0], 0x2000);
  EXPECT_EQ(r[1], 0x47F1);
  encode_float(123456.0f, WordOrder::badc, r);
  EXPECT_EQ(r[0], 0xF147);
  EXPECT_EQ(r[1], 0x0020);
  encode_float(123456.0f, WordOrder::dcba, r);
  EXPECT_EQ(r[0], 0x0020);
  EXPECT_EQ(r[1], 0xF147);
  for (WordOrder o : {WordOrder::abcd, WordOrder::cdab, WordOrder::badc, WordOrder::dcba}) {
    for (float v : {0.0f, -1.5f, 123456.0f, 3.14159f, -987.25f}) {
      encode_float(v, o, r);
      EXPECT_EQ(decode_float(r, o), v) << word_order_name(o);
    }
    EXPECT_EQ(parse_word_order(word_order_name(o)), o);
  }
  EXPECT_THROW(parse_word_order("abcd!"), std::invalid_argument);
}

TEST(Encoding, ScaledInt32SaturatesAndKeepsTheSentinelForNoValue) {
  std::uint16_t r[2];
  encode_scaled(-123.456, 100.0, WordOrder::abcd, r);  // 0.01 mm
  EXPECT_EQ(std::int32_t(decode_u32(r, WordOrder::abcd)), -12346);
  EXPECT_DOUBLE_EQ(decode_scaled(r, 100.0, WordOrder::abcd), -123.46);
  encode_scaled(std::nan(""), 100.0, WordOrder::cdab, r);
  EXPECT_EQ(std::int32_t(decode_u32(r, WordOrder::cdab)), kScaledNone);
  EXPECT_TRUE(std::isnan(decode_scaled(r, 100.0, WordOrder::cdab)));
  encode_scaled(-1e12, 100.0, WordOrder::abcd, r);
  EXPECT_EQ(std::int32_t(decode_u32(r, WordOrder::abcd)), kScaledNone + 1);
  encode_scaled(1e12, 100.0, WordOrder::abcd, r);
  EXPECT_EQ(std::int32_t(decode_u32(r, WordOrder::abcd)), INT32_MAX);
}

TEST(Euler, KnownRotations) {
  const Eigen::Matrix3d rz90 = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  auto e = euler_deg(rz90, EulerConvention::zyx);
  EXPECT_NEAR(e[0], 0, 1e-9);
  EXPECT_NEAR(e[1], 0, 1e-9);
  EXPECT_NEAR(e[2], 90, 1e-9);
  // KUKA A=30 B=20 C=10 is Rz(30) Ry(20) Rx(10).
  const Eigen::Matrix3d kuka = (Eigen::AngleAxisd(30 * M_PI / 180, Eigen::Vector3d::UnitZ()) *
                                Eigen::AngleAxisd(20 * M_PI / 180, Eigen::Vector3d::UnitY()) *
                                Eigen::AngleAxisd(10 * M_PI / 180, Eigen::Vector3d::UnitX()))
                                   .toRotationMatrix();
  e = euler_deg(kuka, EulerConvention::zyx);
  EXPECT_NEAR(e[0], 10, 1e-9);
  EXPECT_NEAR(e[1], 20, 1e-9);
  EXPECT_NEAR(e[2], 30, 1e-9);
  // The same matrix in XYZ intrinsic angles is something else, and composes back to it.
  e = euler_deg(kuka, EulerConvention::xyz);
  EXPECT_TRUE(rotation_from_euler_deg(e, EulerConvention::xyz).isApprox(kuka, 1e-9));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-170, 170), v(-85, 85);
  for (int i = 0; i < 200; ++i)
    for (EulerConvention c : {EulerConvention::zyx, EulerConvention::xyz}) {
      const std::array<double, 3> in{u(rng), v(rng), u(rng)};
      const Eigen::Matrix3d r = rotation_from_euler_deg(in, c);
      EXPECT_TRUE(rotation_from_euler_deg(euler_deg(r, c), c).isApprox(r, 1e-9));
    }
  // Gimbal lock still composes back.
  const Eigen::Matrix3d lock = rotation_from_euler_deg({15, 90, 40}, EulerConvention::zyx);
  EXPECT_TRUE(rotation_from_euler_deg(euler_deg(lock, EulerConvention::zyx), EulerConvention::zyx)
                  .isApprox(lock, 1e-6));
}

TEST(RobotPose, HandEyeAndGraspOffsetAndQuaternion) {
  Pose model_to_cam = Pose::Identity();
  model_to_cam.translation() = Eigen::Vector3d(10, 20, 1000);
  Pose robot_from_cam = Pose::Identity();
  robot_from_cam.linear() = Eigen::Vector3d(1, -1, -1).asDiagonal();  // camera looking down
  robot_from_cam.translation() = Eigen::Vector3d(500, 0, 1200);
  Pose grasp = Pose::Identity();
  grasp.translation() = Eigen::Vector3d(0, 0, 5);
  const RobotPose p = to_robot(model_to_cam, robot_from_cam, grasp, EulerConvention::zyx);
  EXPECT_NEAR(p.xyz_mm[0], 510, 1e-9);
  EXPECT_NEAR(p.xyz_mm[1], -20, 1e-9);
  EXPECT_NEAR(p.xyz_mm[2], 1200 - 1005, 1e-9);
  EXPECT_NEAR(std::abs(p.rxyz_deg[0]), 180, 1e-9);  // half a turn about x
  EXPECT_GE(p.wxyz[0], 0);
  EXPECT_NEAR(std::abs(p.wxyz[1]), 1, 1e-9);
}

TEST(RegisterMap, PoseIsNaNUnlessDoneOk) {
  reg::Result r;
  r.status = reg::Status::done_ok;
  r.pose = RobotPose{{1, 2, 3}, {4, 5, 6}, {1, 0, 0, 0}};
  r.score = 0.75f;
  r.cycles = 70000;
  std::uint16_t map[reg::kSize] = {};
  reg::Encoding enc;
  reg::write_result_block(r, enc, map);
  EXPECT_FLOAT_EQ(decode_float(&map[reg::kPose + 4], enc.order), 3.0f);
  EXPECT_FLOAT_EQ(decode_float(&map[reg::kScore], enc.order), 0.75f);
  EXPECT_EQ(decode_u32(&map[reg::kCycles], enc.order), 70000u);
  r.status = reg::Status::done_none;  // a pose left in the struct must not reach the registers
  reg::write_result_block(r, enc, map);
  for (int i = reg::kPose; i < reg::kPoseEnd; i += 2)
    EXPECT_TRUE(std::isnan(decode_float(&map[i], enc.order))) << i;
  enc.scaled_int32 = true;
  reg::write_result_block(r, enc, map);
  for (int i = reg::kPose; i < reg::kPoseEnd; i += 2)
    EXPECT_EQ(std::int32_t(decode_u32(&map[i], enc.order)), kScaledNone);
  r.status = reg::Status::done_ok;
  reg::write_result_block(r, enc, map);
  EXPECT_EQ(std::int32_t(decode_u32(&map[reg::kPose], enc.order)), 100);       // 1 mm in 0.01 mm
  EXPECT_EQ(std::int32_t(decode_u32(&map[reg::kPose + 6], enc.order)), 4000);  // 4 deg in 0.001 deg
  EXPECT_EQ(std::int32_t(decode_u32(&map[reg::kScore], enc.order)), 7500);
}

// HELD, HELD_WHY and REGIONS are counts, written whatever the status: a DONE_NONE says what the
// LOCATE saw and held back.
TEST(RegisterMap, WhatWasHeldBackIsWrittenWithEveryResult) {
  reg::Result r;
  r.status = reg::Status::done_none;
  r.held = 3, r.held_why = 0x81, r.regions = 7;
  std::uint16_t map[reg::kSize] = {};
  for (const bool scaled : {false, true}) {
    reg::Encoding enc;
    enc.scaled_int32 = scaled;
    reg::write_result_block(r, enc, map);
    EXPECT_EQ(map[reg::kHeld], 3);
    EXPECT_EQ(map[reg::kHeldWhy], 0x81);  // ambiguous, took nothing
    EXPECT_EQ(map[reg::kRegions], 7);
  }
  reg::write_initial(reg::Encoding{}, map);
  EXPECT_EQ(map[reg::kHeld], 0);
  EXPECT_EQ(map[reg::kRegions], 0);
}

}  // namespace
}  // namespace pipeloc

namespace pipeloc {
namespace {

// The worked example of firmware-host/REGISTERS.md, register for register.
TEST(RegistersDoc, WorkedExampleMatchesTheEncoder) {
  Pose pose = Pose::Identity();
  pose.linear() = rotation_from_euler_deg({170, -5, 30}, EulerConvention::zyx);
  pose.translation() = Eigen::Vector3d(412.5, -87.25, 1010);
  reg::Result r;
  r.status = reg::Status::done_ok;
  r.pose = to_robot(pose, Pose::Identity(), Pose::Identity(), EulerConvention::zyx);
  r.score = 0.875f;
  std::uint16_t map[reg::kSize] = {};
  reg::write_result_block(r, reg::Encoding{}, map);
  const std::uint16_t abcd[] = {0x43CE, 0x4000, 0xC2AE, 0x8000, 0x447C, 0x8000, 0x432A, 0x0000,
                                0xC0A0, 0x0000, 0x41F0, 0x0000, 0x3F60, 0x0000, 0x3D95, 0x3740,
                                0x3F76, 0x5A7E, 0x3E82, 0x015C, 0x3D84, 0x1D39};
  for (int i = 0; i < 22; ++i) {
    // The angles come back through a rotation matrix: allow the last bit of the mantissa.
    const int diff = std::abs(int(map[reg::kPose + i]) - int(abcd[i]));
    EXPECT_LE(diff, i % 2 ? 2 : 0) << "register " << reg::kPose + i;
  }
  reg::Encoding scaled;
  scaled.scaled_int32 = true;
  reg::write_result_block(r, scaled, map);
  const std::int32_t ints[] = {41250, -8725, 101000, 170000, -5000, 30000, 8750, 729, 9623, 2539, 645};
  for (int i = 0; i < 11; ++i) {
    const std::uint16_t* at = &map[reg::kPose + 2 * i];
    EXPECT_EQ(std::int32_t(decode_u32(at, WordOrder::abcd)), ints[i]) << "register " << reg::kPose + 2 * i;
  }
}


// MBAP framing and the request checks that keep modbus_reply() off its flushing path.
TEST(ModbusRequest, FramedByTheMbapLengthAndCheckedAgainstTheFunctionCode) {
  auto adu = [](std::initializer_list<int> pdu) {
    std::vector<std::uint8_t> a = {0x12, 0x34, 0, 0, 0, std::uint8_t(pdu.size() + 1), 1};
    for (int b : pdu) a.push_back(std::uint8_t(b));
    return a;
  };
  const auto read = adu({3, 0, 10, 0, 4});
  EXPECT_EQ(mbtcp::adu_bytes(read.data()), 12);
  EXPECT_EQ(mbtcp::request_exception(read.data(), 12), 0);
  std::vector<std::uint8_t> bad_protocol = read;
  bad_protocol[3] = 1;
  EXPECT_EQ(mbtcp::adu_bytes(bad_protocol.data()), -1);
  const std::uint8_t too_long[7] = {0, 1, 0, 0, 0x01, 0x00, 1};  // 256 > 254
  EXPECT_EQ(mbtcp::adu_bytes(too_long), -1);
  const std::uint8_t too_short[7] = {0, 1, 0, 0, 0, 1, 1};  // unit id without a function code
  EXPECT_EQ(mbtcp::adu_bytes(too_short), -1);
  // FC16 writing CMD and REQ_ID: well-formed; a byte missing or a count that disagrees: 03.
  const auto write = adu({16, 0, 0, 0, 2, 4, 0, 1, 0, 7});
  EXPECT_EQ(mbtcp::request_exception(write.data(), int(write.size())), 0);
  const auto short_write = adu({16, 0, 0, 0, 2, 4, 0, 1, 0});
  EXPECT_EQ(mbtcp::request_exception(short_write.data(), int(short_write.size())), 3);
  const auto bad_count = adu({16, 0, 0, 0, 2, 2, 0, 1});
  EXPECT_EQ(mbtcp::request_exception(bad_count.data(), int(bad_count.size())), 3);
  const auto too_many = adu({3, 0, 0, 0, 126});
  EXPECT_EQ(mbtcp::request_exception(too_many.data(), int(too_many.size())), 3);
  for (int fc : {0, 7, 8, 0x2B, 0x80, 0xFF}) {
    const auto unknown = adu({fc, 0, 0, 0, 1});
    EXPECT_EQ(mbtcp::request_exception(unknown.data(), int(unknown.size())), 1) << fc;
  }
}

}  // namespace
}  // namespace pipeloc
