// A procedure's recovery file (tools/procedure/recovery_file.hpp): read back
// as written; a damaged, cut or foreign file is refused with the reason; a
// recovery for another procedure or config is refused naming which.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "read_file.hpp"
#include "tools/procedure/recovery_file.hpp"

using namespace rigctl;

namespace {

std::string path_in(const std::string& name) {
  const auto dir = std::filesystem::path(::testing::TempDir()) / "recovery-file";
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

std::string error_reading(const std::string& path) {
  try {
    read_recovery_file(path);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no error";
}

const RecoveryIdentity kId{"proc.yaml", "00000000000000aa", "rig.yaml", "00000000000000bb"};

}  // namespace

TEST(RecoveryFile, ReadsBackWhatWasWritten) {
  auto r = std::make_unique<ProcedureRecovery>();
  r->sequence = 42;
  r->status.step = 3;
  r->status.total_cycles = 12345;
  r->valley_command[7] = -0.25;
  r->rainflow_channels = 1;
  r->rainflow[0].size = 2;
  r->rainflow[0].points[1] = 0.125;
  r->rainflow[0].committed.damage = 9.5;
  const std::string p = path_in("ok.recovery");
  write_recovery_file(p, kId, *r);
  EXPECT_FALSE(std::filesystem::exists(p + ".tmp"));
  const RecoveryFile f = read_recovery_file(p);
  EXPECT_EQ(f.identity.procedure_hash, kId.procedure_hash);
  EXPECT_EQ(f.identity.config_path, "rig.yaml");
  EXPECT_EQ(f.recovery.sequence, 42u);
  EXPECT_EQ(f.recovery.status.total_cycles, 12345);
  EXPECT_EQ(f.recovery.valley_command[7], -0.25);
  EXPECT_EQ(f.recovery.rainflow[0].points[1], 0.125);
  EXPECT_EQ(f.recovery.rainflow[0].committed.damage, 9.5);
  EXPECT_NE(test::read_file(p).find("total_cycles: 12345\n"), std::string::npos);  // readable head
}

TEST(RecoveryFile, DamagedCutOrForeignFilesAreRefused) {
  auto r = std::make_unique<ProcedureRecovery>();
  const std::string p = path_in("bad.recovery");
  write_recovery_file(p, kId, *r);
  std::string bytes = test::read_file(p);
  std::string flipped = bytes;
  flipped[flipped.size() - 100] ^= 0x5a;
  std::ofstream(p, std::ios::binary | std::ios::trunc) << flipped;
  EXPECT_NE(error_reading(p).find("fails its checksum"), std::string::npos) << error_reading(p);
  std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() - 10);
  EXPECT_NE(error_reading(p).find("cut short"), std::string::npos) << error_reading(p);
  std::ofstream(p, std::ios::binary | std::ios::trunc) << "t,x\n0,1\n";
  EXPECT_NE(error_reading(p).find("is not a rigctl recovery file"), std::string::npos) << error_reading(p);
}

TEST(RecoveryFile, AnotherProcedureOrConfigIsRefusedNamingWhich) {
  RecoveryFile f;
  f.identity = kId;
  RecoveryIdentity other = kId;
  other.procedure_hash = "00000000000000cc";
  try {
    check_recovery_identity(f, other, "x.recovery");
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("was written for procedure proc.yaml"), std::string::npos) << e.what();
  }
  other = kId;
  other.config_hash = "00000000000000dd";
  try {
    check_recovery_identity(f, other, "x.recovery");
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("was written for config rig.yaml"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(check_recovery_identity(f, kId, "x.recovery"));
}
