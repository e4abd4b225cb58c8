// The Part 21 text parser: every parameter kind, complex instances, comments, string escapes,
// errors with their line numbers, and every bundled and corpus STEP file.

#include "model/step/part21.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace rdmesh::step {
namespace {

namespace fs = std::filesystem;

// A whole file around `data`, the DATA section's instances; the header takes lines 1-7, so the
// first line of `data` is line 8.
std::string Wrap(const std::string& data) {
  return "ISO-10303-21;\n"
         "HEADER;\n"
         "FILE_DESCRIPTION((''),'2;1');\n"
         "FILE_NAME('t.step','2024-01-01T00:00:00',(''),(''),'','','');\n"
         "FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));\n"
         "ENDSEC;\n"
         "DATA;\n" +
         data + "ENDSEC;\nEND-ISO-10303-21;\n";
}

File ParseOk(const std::string& bytes) {
  Result<File> file = Parse(bytes);
  EXPECT_TRUE(file.ok()) << file.status().ToString();
  return file.ok() ? std::move(*file) : File();
}

// The message of a refused file ("" when it parsed).
std::string ParseError(const std::string& bytes) {
  Result<File> file = Parse(bytes);
  if (file.ok()) return "";
  EXPECT_EQ(file.status().code(), StatusCode::kParseError);
  return file.status().message();
}

TEST(Part21Test, ReadsEveryParameterKind) {
  File f =
      ParseOk(Wrap("#1=THING($,*,12,-3,+4,1.5,-0.,1.E-07,.5,-2.5E+3,'it''s',.T.,\"0A1\",#7,"
                   "(1,(2,3),()),LENGTH_MEASURE(1.),.UNSPECIFIED.);\n"
                   "#7=POINT('',(0.,1.,2.));\n"));
  ASSERT_EQ(f.instances.size(), 2u);
  EXPECT_EQ(f.schemas, std::vector<std::string>{"AUTOMOTIVE_DESIGN"});
  const Instance* one = f.Find(1);
  ASSERT_NE(one, nullptr);
  EXPECT_EQ(one->line, 8u);
  const Record* r = f.RecordOf(*one);
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(f.TypeName(*r), "THING");
  ASSERT_EQ(r->param_count, 17u);
  EXPECT_EQ(f.Arg(*r, 17), nullptr);

  EXPECT_EQ(f.Arg(*r, 0)->kind, ParamKind::kUnset);
  EXPECT_EQ(f.Arg(*r, 1)->kind, ParamKind::kDerived);
  EXPECT_EQ(f.Arg(*r, 2)->kind, ParamKind::kInteger);
  EXPECT_EQ(f.Arg(*r, 2)->value.integer, 12);
  EXPECT_EQ(f.Arg(*r, 3)->value.integer, -3);
  EXPECT_EQ(f.Arg(*r, 4)->value.integer, 4);
  const double reals[] = {1.5, -0.0, 1e-7, 0.5, -2500.0};
  for (int i = 0; i < 5; ++i) {
    const Param* p = f.Arg(*r, 5 + i);
    ASSERT_EQ(p->kind, ParamKind::kReal) << i;
    EXPECT_EQ(p->value.real, reals[i]) << i;
  }
  EXPECT_TRUE(std::signbit(f.Arg(*r, 6)->value.real));
  EXPECT_EQ(f.Arg(*r, 10)->kind, ParamKind::kString);
  EXPECT_EQ(f.Text(*f.Arg(*r, 10)), "it''s");
  EXPECT_EQ(DecodeString(f.Text(*f.Arg(*r, 10))), "it's");
  EXPECT_EQ(f.Arg(*r, 11)->kind, ParamKind::kEnum);
  EXPECT_EQ(f.Text(*f.Arg(*r, 11)), "T");
  EXPECT_EQ(f.Arg(*r, 12)->kind, ParamKind::kBinary);
  EXPECT_EQ(f.Text(*f.Arg(*r, 12)), "0A1");
  EXPECT_EQ(f.Arg(*r, 13)->kind, ParamKind::kRef);
  EXPECT_EQ(f.Arg(*r, 13)->value.ref, 7u);

  const Param* list = f.Arg(*r, 14);
  ASSERT_EQ(list->kind, ParamKind::kList);
  ASSERT_EQ(list->count, 3u);
  EXPECT_EQ(f.Item(*list, 0)->value.integer, 1);
  const Param* inner = f.Item(*list, 1);
  ASSERT_EQ(inner->kind, ParamKind::kList);
  ASSERT_EQ(inner->count, 2u);
  EXPECT_EQ(f.Item(*inner, 0)->value.integer, 2);
  EXPECT_EQ(f.Item(*inner, 1)->value.integer, 3);
  EXPECT_EQ(f.Item(*inner, 2), nullptr);
  EXPECT_EQ(f.Item(*list, 2)->kind, ParamKind::kList);
  EXPECT_EQ(f.Item(*list, 2)->count, 0u);
  EXPECT_EQ(f.Item(*list, 3), nullptr);
  EXPECT_EQ(f.Item(*f.Arg(*r, 2), 0), nullptr);  // an integer has no items

  const Param* typed = f.Arg(*r, 15);
  ASSERT_EQ(typed->kind, ParamKind::kTyped);
  EXPECT_EQ(f.TypedName(*typed), "LENGTH_MEASURE");
  ASSERT_NE(f.Item(*typed, 0), nullptr);
  EXPECT_EQ(f.Item(*typed, 0)->kind, ParamKind::kReal);
  EXPECT_EQ(f.Item(*typed, 0)->value.real, 1.0);
  EXPECT_EQ(f.Text(*f.Arg(*r, 16)), "UNSPECIFIED");
  EXPECT_EQ(f.TypedName(*list), "");
  EXPECT_EQ(f.Text(*list), "");

  const Instance* seven = f.Find(7);
  ASSERT_NE(seven, nullptr);
  EXPECT_EQ(seven->line, 9u);
  const Param* xyz = f.Arg(*f.RecordOf(*seven), 1);
  ASSERT_EQ(xyz->count, 3u);
  EXPECT_EQ(f.Item(*xyz, 2)->value.real, 2.0);
  EXPECT_EQ(f.Find(2), nullptr);
  EXPECT_EQ(f.Find(1u << 30), nullptr);
}

TEST(Part21Test, ReadsComplexInstancesCommentsAndLowerCase) {
  File f = ParseOk(Wrap(
      "/* a comment */ #3 = ( GEOMETRIC_REPRESENTATION_CONTEXT(3)\r\n"
      "  GLOBAL_UNIT_ASSIGNED_CONTEXT((#4,#5)) /* inside */ REPRESENTATION_CONTEXT('',''));\r\n"
      "#4=( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) );\n"
      "#5 /*x*/ = /*y*/ plane ( /* z */ 'p' /*,*/ , #4 ) /* ; */ ;\n"
      "/* a comment\n over lines with 'quotes' and #9=X(); */\n"));
  ASSERT_EQ(f.instances.size(), 3u);
  const Instance* three = f.Find(3);
  ASSERT_NE(three, nullptr);
  EXPECT_EQ(three->line, 8u);
  ASSERT_EQ(three->record_count, 3u);
  EXPECT_EQ(f.TypeName(*f.RecordOf(*three)), "GEOMETRIC_REPRESENTATION_CONTEXT");
  const Record* units = f.RecordOf(*three, "global_unit_assigned_context");
  ASSERT_NE(units, nullptr);
  EXPECT_EQ(f.TypeName(*units), "GLOBAL_UNIT_ASSIGNED_CONTEXT");
  EXPECT_EQ(f.Item(*f.Arg(*units, 0), 1)->value.ref, 5u);
  EXPECT_EQ(f.RecordOf(*three, "PLANE"), nullptr);
  const Record* context = f.RecordOf(*three, "REPRESENTATION_CONTEXT");
  ASSERT_NE(context, nullptr);
  EXPECT_EQ(context->param_count, 2u);

  const Instance* four = f.Find(4);
  ASSERT_EQ(four->record_count, 3u);
  EXPECT_EQ(f.RecordOf(*four, "LENGTH_UNIT")->param_count, 0u);
  EXPECT_EQ(f.Text(*f.Arg(*f.RecordOf(*four, "SI_UNIT"), 1)), "METRE");

  const Instance* five = f.Find(5);
  EXPECT_EQ(five->line, 11u);
  const Record* plane = f.RecordOf(*five, "ANY");  // a simple instance: its only record
  ASSERT_NE(plane, nullptr);
  EXPECT_EQ(f.TypeName(*plane), "plane");
  ASSERT_EQ(plane->param_count, 2u);
  EXPECT_EQ(f.Text(*f.Arg(*plane, 0)), "p");
  EXPECT_EQ(f.Find(9), nullptr);  // inside a comment
}

TEST(Part21Test, SortsAndIndexesIds) {
  File dense = ParseOk(Wrap("#30=A(1);\n#10=A(2);\n#20=A(3);\n"));
  ASSERT_EQ(dense.instances.size(), 3u);
  EXPECT_EQ(dense.instances[0].id, 10u);
  EXPECT_EQ(dense.instances[2].id, 30u);
  EXPECT_FALSE(dense.dense_index.empty());
  EXPECT_EQ(dense.Arg(*dense.RecordOf(*dense.Find(20)), 0)->value.integer, 3);
  EXPECT_EQ(dense.Arg(*dense.RecordOf(*dense.Find(30)), 0)->value.integer, 1);
  EXPECT_EQ(dense.Find(31), nullptr);

  File sparse = ParseOk(Wrap("#5000000000=A(1);\n#7=A(#123456789);\n"));
  EXPECT_TRUE(sparse.dense_index.empty());
  ASSERT_NE(sparse.Find(5000000000u), nullptr);
  EXPECT_EQ(sparse.Find(5000000000u)->line, 8u);
  EXPECT_EQ(sparse.Find(7)->line, 9u);
  EXPECT_EQ(sparse.Find(8), nullptr);
  // A reference to a missing instance is the translator's to report.
  EXPECT_EQ(sparse.Find(sparse.Arg(*sparse.RecordOf(*sparse.Find(7)), 0)->value.ref), nullptr);
}

TEST(Part21Test, ReadsSeveralDataSectionsAndEditionThreeHeaders) {
  File f = ParseOk(
      "\xEF\xBB\xBFISO-10303-21;\nHEADER;\nFILE_SCHEMA(('CONFIG_CONTROL_DESIGN','AP242'));\n"
      "ENDSEC;\nDATA('one',('CONFIG_CONTROL_DESIGN'));\n#1=A();\nENDSEC;\nDATA;\n#2=B(#1);\n"
      "ENDSEC;\nEND-ISO-10303-21;\ntrailing bytes are ignored");
  EXPECT_EQ(f.schemas, (std::vector<std::string>{"CONFIG_CONTROL_DESIGN", "AP242"}));
  ASSERT_EQ(f.instances.size(), 2u);
  EXPECT_EQ(f.Find(2)->line, 9u);
  EXPECT_EQ(f.Arg(*f.RecordOf(*f.Find(2)), 0)->value.ref, 1u);
  EXPECT_EQ(f.params.size(), 1u);  // DATA's own parameters are not kept
}

TEST(Part21Test, DecodesStrings) {
  EXPECT_EQ(DecodeString(""), "");
  EXPECT_EQ(DecodeString("plain"), "plain");
  EXPECT_EQ(DecodeString("a''b"), "a'b");
  EXPECT_EQ(DecodeString("a\\\\b"), "a\\b");
  EXPECT_EQ(DecodeString("\\S\\D"), "\xC3\x84");     // 'D' + 128 = U+00C4
  EXPECT_EQ(DecodeString("\\S\\''x"), "\xC2\xA7x");  // a doubled quote + 128 = U+00A7
  EXPECT_EQ(DecodeString("\\X\\E9t\\X\\e9"), "\xC3\xA9t\xC3\xA9");
  EXPECT_EQ(DecodeString("\\X2\\00E9004B\\X0\\!"), "\xC3\xA9K!");
  EXPECT_EQ(DecodeString("\\X2\\D83DDE00\\X0\\"), "\xF0\x9F\x98\x80");  // a surrogate pair
  EXPECT_EQ(DecodeString("\\X2\\D83D0041\\X0\\"),
            "\xEF\xBF\xBD"
            "A");  // a lone high surrogate
  EXPECT_EQ(DecodeString("\\X4\\0001F600\\X0\\"), "\xF0\x9F\x98\x80");
  EXPECT_EQ(DecodeString("\\X4\\00110000\\X0\\"), "\xEF\xBF\xBD");
  EXPECT_EQ(DecodeString("\\PA\\x\\PB\\"), "x");
  EXPECT_EQ(DecodeString("ab\r\ncd"), "abcd");
  EXPECT_EQ(DecodeString("\xE2\x82\xAC"), "\xE2\x82\xAC");  // UTF-8 passes through
  // Invalid escapes stay as written.
  EXPECT_EQ(DecodeString("\\X\\G1"), "\\X\\G1");
  EXPECT_EQ(DecodeString("\\X2\\00E9"), "\\X2\\00E9");
  EXPECT_EQ(DecodeString("\\X2\\00E\\X0\\"), "\\X2\\00E\\X0\\");
  EXPECT_EQ(DecodeString("\\Q\\"), "\\Q\\");
  EXPECT_EQ(DecodeString("\\"), "\\");
  EXPECT_EQ(DecodeString("\\S\\"), "\\S\\");
  EXPECT_EQ(DecodeString("\\PZ\\"), "\\PZ\\");
}

TEST(Part21Test, RefusesMalformedFilesWithTheLine) {
  EXPECT_EQ(ParseError(Wrap("#1=A(1);\n")), "");
  // Truncated in the middle of an instance.
  std::string whole = Wrap("#1=A(1);\n#2=B((1,2),\n'x');\n");
  EXPECT_EQ(ParseError(whole.substr(0, whole.find("2),") + 1)),
            "line 9: expected ',' or ')' after a parameter, found the end of the file");
  EXPECT_EQ(ParseError(Wrap("#1=A('abc);\n#2=B();\n")), "line 8: unterminated string");
  EXPECT_EQ(ParseError(whole.substr(0, whole.find("END-ISO"))),
            "line 12: expected DATA; or END-ISO-10303-21;, found the end of the file");
  EXPECT_EQ(ParseError(Wrap("#1=A(1);\n\n#1=B(2);\n")),
            "line 10: instance #1 is defined twice (first on line 8)");
  EXPECT_EQ(ParseError(Wrap("#2=A(1);\n#1=C();\n#2=B(2);\n")),
            "line 10: instance #2 is defined twice (first on line 8)");
  EXPECT_EQ(ParseError(Wrap("#1=A(" + std::string(kMaxNesting, '(') +
                            std::string(kMaxNesting, ')') + ");\n")),
            "");
  EXPECT_EQ(ParseError(Wrap("\n#1=A(" + std::string(kMaxNesting + 1, '(') +
                            std::string(kMaxNesting + 1, ')') + ");\n")),
            "line 9: lists nested deeper than 64");
  EXPECT_EQ(ParseError(Wrap("#1=A(X(" + std::string(kMaxNesting, '(') + "1" +
                            std::string(kMaxNesting, ')') + "));\n")),
            "line 8: lists nested deeper than 64");
  // A deep nesting ends before it costs the stack anything.
  EXPECT_EQ(ParseError(Wrap("#1=A(" + std::string(1000000, '('))),
            "line 8: lists nested deeper than 64");
  EXPECT_EQ(ParseError(Wrap("#1=A(1.5D3);\n")),
            "line 8: a 'D' exponent is not Part 21 (reals use 'E', as in 1.5E3)");
  EXPECT_EQ(ParseError(Wrap("#1=A(1.E+999);\n")), "line 8: real number out of range");
  File tiny = ParseOk(Wrap("#1=A(1.E-999,-1.E-999);\n"));  // too small to hold is zero
  ASSERT_EQ(tiny.params.size(), 2u);
  EXPECT_EQ(tiny.params[0].value.real, 0.0);
  EXPECT_TRUE(std::signbit(tiny.params[1].value.real));
  EXPECT_EQ(ParseError(Wrap("#1=A(99999999999999999999);\n")), "line 8: integer out of range");
  EXPECT_EQ(ParseError(Wrap("#1=A(1 2);\n")),
            "line 8: expected ',' or ')' after a parameter, found '2'");
  EXPECT_EQ(ParseError(Wrap("#1=A(1,);\n")), "line 8: expected a parameter, found ')'");
  EXPECT_EQ(ParseError(Wrap("#1=A(12ab);\n")), "line 8: malformed number");
  EXPECT_EQ(ParseError(Wrap("#1=A(.T);\n")), "line 8: expected an enumeration .NAME., found ')'");
  EXPECT_EQ(ParseError(Wrap("#1=A(\"0G\");\n")),
            "line 8: expected hexadecimal digits or '\"' in a binary, found 'G'");
  EXPECT_EQ(ParseError(Wrap("#1=A(X(1,2));\n")),
            "line 8: a typed parameter holds exactly one value");
  EXPECT_EQ(ParseError(Wrap("#1=();\n")), "line 8: a complex instance needs at least one record");
  EXPECT_EQ(ParseError(Wrap("#=A();\n")), "line 8: expected digits after '#', found '='");
  EXPECT_EQ(ParseError(Wrap("#1 A();\n")),
            "line 8: expected '=' after the instance name, found 'A'");
  EXPECT_EQ(ParseError(Wrap("#1=A()\n#2=B();\n")),
            "line 9: expected ';' after an instance, found '#'");
  EXPECT_EQ(ParseError(Wrap("#1=A(1);\n/* never closed\n#2=B();\n")),
            "line 9: expected an instance '#N=' or ENDSEC, found an unterminated comment");
  EXPECT_EQ(ParseError(Wrap(std::string("#1=A(1,\0);\n", 11))),
            "line 8: expected a parameter, found byte 0x00");
  EXPECT_EQ(ParseError("solid cube\nendsolid\n"),
            "line 1: expected ISO-10303-21; at the start of a STEP file, found 's'");
  EXPECT_EQ(
      ParseError(""),
      "line 1: expected ISO-10303-21; at the start of a STEP file, found the end of the file");
  EXPECT_EQ(ParseError("ISO-10303-21;\nHEADER;\nFILE_SCHEMA(('X'));\nDATA;\n"),
            "line 4: expected ENDSEC; to end the header, found 'D'");
}

TEST(Part21Test, StopsWhenTheContextSaysSo) {
  std::string data;
  for (int i = 1; i <= 60000; ++i)
    data += "#" + std::to_string(i) + "=CARTESIAN_POINT('',(1.,2.,3.));\n";
  const std::string bytes = Wrap(data);
  ASSERT_GT(bytes.size(), size_t{2} << 20);
  Context context;
  EXPECT_TRUE(Parse(bytes, &context).ok());
  context.Cancel();
  Result<File> cancelled = Parse(bytes, &context);
  EXPECT_EQ(cancelled.status().code(), StatusCode::kCancelled);
}

// The instances of a file counted without the parser: '#' digits blanks '=' outside strings and
// comments.
size_t CountInstances(const std::string& s) {
  size_t count = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '\'') {
      i = s.find('\'', i + 1);  // '' is two strings back to back: the same count
      if (i == std::string::npos) return count;
    } else if (s[i] == '/' && i + 1 < s.size() && s[i + 1] == '*') {
      i = s.find("*/", i + 2);
      if (i == std::string::npos) return count;
      ++i;
    } else if (s[i] == '#') {
      size_t j = i + 1;
      while (j < s.size() && s[j] >= '0' && s[j] <= '9') ++j;
      if (j == i + 1) continue;
      while (j < s.size() && (s[j] == ' ' || s[j] == '\r' || s[j] == '\n' || s[j] == '\t')) ++j;
      if (j < s.size() && s[j] == '=') ++count;
    }
  }
  return count;
}

TEST(Part21Test, CountHelperCounts) {
  EXPECT_EQ(CountInstances("#1=A('#2=B()');/* #3=C(); */#4 =D(#5);"), 2u);
}

void ExpectAllParse(const fs::path& dir, size_t* files) {
  for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".step" && ext != ".stp" && ext != ".STEP" && ext != ".STP") continue;
    std::ifstream in(entry.path(), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const size_t expected = CountInstances(bytes);
    Result<File> file = Parse(bytes);
    ASSERT_TRUE(file.ok()) << entry.path() << ": " << file.status().ToString();
    EXPECT_EQ(file->instances.size(), expected) << entry.path();
    EXPECT_GT(expected, 0u) << entry.path();
    EXPECT_FALSE(file->schemas.empty()) << entry.path();
    for (size_t i = 1; i < file->instances.size(); ++i) {
      ASSERT_LT(file->instances[i - 1].id, file->instances[i].id) << entry.path();
    }
    ++*files;
  }
}

TEST(Part21Test, ParsesTheBundledModels) {
  size_t files = 0;
  ExpectAllParse(RDMESH_TEST_DATA, &files);
  EXPECT_GE(files, 4u);
}

TEST(Part21Test, ParsesTheCorpus) {
  const fs::path corpus = fs::path(RDMESH_SHARED_DIR) / "corpus";
  if (!fs::is_directory(corpus)) GTEST_SKIP() << corpus << " is missing";
  size_t files = 0;
  ExpectAllParse(corpus, &files);
  EXPECT_GE(files, 1u);
}

}  // namespace
}  // namespace rdmesh::step
