// io/batch_summary.h: the rows of summary.jsonl and summary.csv.

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "io/batch_summary.h"
#include "io/errors.h"
#include "temp_dir_test.h"

namespace csgvox {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

SummaryRow okRow() {
  SummaryRow row;
  row.path = "data/flange/scan.ply";
  row.output = "out/flange/scan";
  row.seconds = 2.5;
  row.primitives = 12;
  row.operations = 5;
  row.chamfer = 0.1;
  row.chamferRelative = 0.001;
  row.voxelIou = 0.98;
  return row;
}

SummaryRow errorRow() {
  SummaryRow row;
  row.path = "a \"b\",c.ply";
  row.output = "out/a";
  row.status = RowStatus::Error;
  row.error = "a \"b\",c.ply: truncated, 3 of 5 vertices";
  row.seconds = 0.25;
  return row;
}

class BatchSummary : public test::TempDirTest {};

TEST_F(BatchSummary, RowsAsJsonAndCsv) {
  const nlohmann::ordered_json j = rowJson(okRow());
  std::vector<std::string> keys;
  for (const auto& [key, value] : j.items()) keys.push_back(key);
  EXPECT_EQ(keys, summaryColumns());
  EXPECT_EQ(j.dump(),
            "{\"path\":\"data/flange/scan.ply\",\"output\":\"out/flange/scan\",\"status\":\"ok\","
            "\"error\":null,\"seconds\":2.5,\"primitives\":12,\"operations\":5,\"chamfer\":0.1,"
            "\"chamfer_relative\":0.001,\"voxel_iou\":0.98}");
  EXPECT_EQ(rowCsv(okRow()), "data/flange/scan.ply,out/flange/scan,ok,,2.5,12,5,0.1,0.001,0.98");
  // Quotes doubled, cells with commas or quotes quoted, missing figures empty.
  EXPECT_EQ(rowCsv(errorRow()),
            "\"a \"\"b\"\",c.ply\",out/a,error,\"a \"\"b\"\",c.ply: truncated, 3 of 5 vertices\","
            "0.25,,,,,");
  const nlohmann::ordered_json e = rowJson(errorRow());
  EXPECT_EQ(e["status"], "error");
  EXPECT_TRUE(e["primitives"].is_null());
  EXPECT_TRUE(e["voxel_iou"].is_null());
}

TEST_F(BatchSummary, WriterAppendsKeepsAndCutsATornLine) {
  {
    SummaryWriter w(dir_, false);
    w.append(okRow());
  }
  EXPECT_EQ(slurp(dir_ / "summary.csv"),
            "path,output,status,error,seconds,primitives,operations,chamfer,chamfer_relative,"
            "voxel_iou\n" +
                rowCsv(okRow()) + "\n");
  // A torn last line (a killed run) is cut when the rows are kept.
  {
    std::ofstream(dir_ / "summary.jsonl", std::ios::app) << "{\"path\":\"x";
    std::ofstream(dir_ / "summary.csv", std::ios::app) << "x,y";
  }
  EXPECT_EQ(readSummaryRows(dir_ / "summary.jsonl").size(), 1u);
  {
    SummaryWriter w(dir_, true);
    w.append(errorRow());
  }
  EXPECT_EQ(slurp(dir_ / "summary.jsonl"),
            rowJson(okRow()).dump() + "\n" + rowJson(errorRow()).dump() + "\n");
  const auto rows = readSummaryRows(dir_ / "summary.jsonl");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows.at(errorRow().path)["status"], "error");
  EXPECT_EQ(slurp(dir_ / "summary.csv").find("x,y"), std::string::npos);
  // Without keeping, a new summary starts.
  { SummaryWriter w(dir_, false); }
  EXPECT_EQ(slurp(dir_ / "summary.jsonl"), "");
  EXPECT_TRUE(readSummaryRows(dir_ / "missing.jsonl").empty());
}

TEST_F(BatchSummary, RowFromReport) {
  write("report.json",
        R"({"status": "ok", "tree": {"primitives": 3, "operations": 2, "depth": 3},
            "metrics": {"voxel_iou": 0.9, "chamfer": 0.5, "chamfer_relative": 0.01},
            "timings_s": {"read": 0.5, "detect": 1.0, "export": 0.25}})");
  SummaryRow row = rowFromReport(dir_ / "report.json", "s.ply", "out/s");
  EXPECT_EQ(row.primitives, 3);
  EXPECT_EQ(row.operations, 2);
  EXPECT_EQ(row.voxelIou, 0.9);
  EXPECT_EQ(row.chamferRelative, 0.01);
  EXPECT_DOUBLE_EQ(row.seconds, 1.75);  // the report's timings
  EXPECT_EQ(rowFromReport(dir_ / "report.json", "s.ply", "out/s", 4.0).seconds, 4.0);
  write("bad.json", R"({"status": "ok"})");
  EXPECT_THROW(rowFromReport(dir_ / "bad.json", "s", "o"), ParseError);
  write("garbage.json", "{");
  EXPECT_THROW(rowFromReport(dir_ / "garbage.json", "s", "o"), ParseError);
  EXPECT_THROW(rowFromReport(dir_ / "missing.json", "s", "o"), IoError);
}

}  // namespace
}  // namespace csgvox
