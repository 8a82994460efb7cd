// MediaLibrary, MediaImage and PatientRecord on files written by the test: DICOM with
// DCMTK (window/level checked against the DICOM linear VOI formula), PNG/JPEG with
// OpenCV, and broken files that must be refused by name.
#include <dcmtk/config/osconfig.h>
#include <dcmtk/dcmdata/dcdeftag.h>
#include <dcmtk/dcmdata/dcfilefo.h>
#include <dcmtk/dcmdata/dcuid.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "endotower/media/media_library.hpp"

namespace endotower::media {
namespace {

namespace fs = std::filesystem;

class MediaTest : public ::testing::Test {
protected:
    void SetUp() override {
        char tmpl[] = "/tmp/endotower_media_XXXXXX";
        ASSERT_NE(mkdtemp(tmpl), nullptr);
        dir_ = tmpl;
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }
    void write(const std::string& name, const std::string& bytes) const {
        std::ofstream(path(name), std::ios::binary) << bytes;
    }
    std::string read(const std::string& name) const {
        std::ifstream in(path(name), std::ios::binary);
        return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    }
    // A 16-bit monochrome DICOM, 4 x 3, values v[i]; window (centre, width) if width > 0.
    void write_dicom(const std::string& name, const std::vector<Uint16>& v, double centre,
                     double width) const {
        DcmFileFormat file;
        DcmDataset* ds = file.getDataset();
        char uid[100];
        ds->putAndInsertString(DCM_SOPClassUID, UID_SecondaryCaptureImageStorage);
        ds->putAndInsertString(DCM_SOPInstanceUID, dcmGenerateUniqueIdentifier(uid, SITE_INSTANCE_UID_ROOT));
        ds->putAndInsertString(DCM_PatientName, "Test^Patient");
        ds->putAndInsertUint16(DCM_Rows, 3);
        ds->putAndInsertUint16(DCM_Columns, 4);
        ds->putAndInsertUint16(DCM_SamplesPerPixel, 1);
        ds->putAndInsertString(DCM_PhotometricInterpretation, "MONOCHROME2");
        ds->putAndInsertUint16(DCM_BitsAllocated, 16);
        ds->putAndInsertUint16(DCM_BitsStored, 12);
        ds->putAndInsertUint16(DCM_HighBit, 11);
        ds->putAndInsertUint16(DCM_PixelRepresentation, 0);
        if (width > 0) {
            ds->putAndInsertString(DCM_WindowCenter, std::to_string(centre).c_str());
            ds->putAndInsertString(DCM_WindowWidth, std::to_string(width).c_str());
        }
        ds->putAndInsertUint16Array(DCM_PixelData, v.data(), static_cast<unsigned long>(v.size()));
        ASSERT_TRUE(file.saveFile(path(name).c_str(), EXS_LittleEndianExplicit).good());
    }
    // An RGB DICOM, 2 x 1.
    void write_colour_dicom(const std::string& name) const {
        DcmFileFormat file;
        DcmDataset* ds = file.getDataset();
        char uid[100];
        ds->putAndInsertString(DCM_SOPClassUID, UID_SecondaryCaptureImageStorage);
        ds->putAndInsertString(DCM_SOPInstanceUID, dcmGenerateUniqueIdentifier(uid, SITE_INSTANCE_UID_ROOT));
        ds->putAndInsertUint16(DCM_Rows, 1);
        ds->putAndInsertUint16(DCM_Columns, 2);
        ds->putAndInsertUint16(DCM_SamplesPerPixel, 3);
        ds->putAndInsertString(DCM_PhotometricInterpretation, "RGB");
        ds->putAndInsertUint16(DCM_PlanarConfiguration, 0);
        ds->putAndInsertUint16(DCM_BitsAllocated, 8);
        ds->putAndInsertUint16(DCM_BitsStored, 8);
        ds->putAndInsertUint16(DCM_HighBit, 7);
        ds->putAndInsertUint16(DCM_PixelRepresentation, 0);
        const Uint8 px[6] = {250, 10, 20, 5, 128, 255};
        ds->putAndInsertUint8Array(DCM_PixelData, px, 6);
        ASSERT_TRUE(file.saveFile(path(name).c_str(), EXS_LittleEndianExplicit).good());
    }
    fs::path dir_;
};

// DICOM PS3.3 C.11.2.1.2.1, the linear VOI function, to 0..255.
double voi_linear(double x, double c, double w) {
    if (x <= c - 0.5 - (w - 1) / 2) return 0;
    if (x > c - 0.5 + (w - 1) / 2) return 255;
    return ((x - (c - 0.5)) / (w - 1) + 0.5) * 255;
}

TEST_F(MediaTest, DicomWindowFromTheFileToGrey) {
    const std::vector<Uint16> v = {0, 100, 500, 900, 1000, 1040, 1100, 1200, 1500, 2000, 3000, 4095};
    write_dicom("ct.dcm", v, 1100, 400);
    MediaImage img;
    std::string error;
    ASSERT_TRUE(load_media_image(path("ct.dcm"), img, error)) << error;
    EXPECT_EQ(img.name, "ct.dcm");
    ASSERT_EQ(img.width, 4);
    ASSERT_EQ(img.height, 3);
    ASSERT_EQ(img.rgba.size(), 48u);
    for (std::size_t i = 0; i < v.size(); ++i) {
        const double expected = voi_linear(v[i], 1100, 400);
        EXPECT_NEAR(img.rgba[4 * i], expected, 1.0) << "value " << v[i];
        EXPECT_EQ(img.rgba[4 * i + 1], img.rgba[4 * i]);
        EXPECT_EQ(img.rgba[4 * i + 2], img.rgba[4 * i]);
        EXPECT_EQ(img.rgba[4 * i + 3], 255);
    }
}

TEST_F(MediaTest, DicomWithoutWindowUsesItsRange) {
    const std::vector<Uint16> v = {200, 300, 400, 500, 600, 700, 800, 900, 1000, 1100, 1200, 1300};
    write_dicom("mr.dcm", v, 0, 0);
    MediaImage img;
    std::string error;
    ASSERT_TRUE(load_media_image(path("mr.dcm"), img, error)) << error;
    EXPECT_EQ(img.rgba[0], 0);
    EXPECT_EQ(img.rgba[4 * 11], 255);
    for (std::size_t i = 1; i < v.size(); ++i) EXPECT_GT(img.rgba[4 * i], img.rgba[4 * (i - 1)]);
}

TEST_F(MediaTest, ColourDicomKeepsItsRgb) {
    write_colour_dicom("rgb.dcm");
    MediaImage img;
    std::string error;
    ASSERT_TRUE(load_media_image(path("rgb.dcm"), img, error)) << error;
    const std::vector<std::uint8_t> expected = {250, 10, 20, 255, 5, 128, 255, 255};
    EXPECT_EQ(img.rgba, expected);
}

TEST_F(MediaTest, PngAndJpeg) {
    cv::Mat bgra(2, 3, CV_8UC4, cv::Scalar(30, 20, 10, 200));  // B G R A
    bgra.at<cv::Vec4b>(1, 2) = {1, 2, 3, 4};
    ASSERT_TRUE(cv::imwrite(path("a.png"), bgra));
    MediaImage img;
    std::string error;
    ASSERT_TRUE(load_media_image(path("a.png"), img, error)) << error;
    ASSERT_EQ(img.width, 3);
    EXPECT_EQ(img.rgba[0], 10);
    EXPECT_EQ(img.rgba[2], 30);
    EXPECT_EQ(img.rgba[3], 200);
    EXPECT_EQ(img.rgba[4 * 5 + 0], 3);
    EXPECT_EQ(img.rgba[4 * 5 + 3], 4);

    cv::Mat grey16(4, 4, CV_16UC1, cv::Scalar(65535));
    ASSERT_TRUE(cv::imwrite(path("g.png"), grey16));
    ASSERT_TRUE(load_media_image(path("g.png"), img, error)) << error;
    EXPECT_EQ(img.rgba[0], 255);

    cv::Mat flat(16, 16, CV_8UC3, cv::Scalar(40, 120, 200));
    ASSERT_TRUE(cv::imwrite(path("c.jpg"), flat));
    ASSERT_TRUE(load_media_image(path("c.jpg"), img, error)) << error;
    EXPECT_NEAR(img.rgba[0], 200, 3);  // lossy: a flat block decodes within a few levels
    EXPECT_NEAR(img.rgba[1], 120, 3);
    EXPECT_NEAR(img.rgba[2], 40, 3);
}

TEST_F(MediaTest, BrokenFilesAreRefusedByName) {
    cv::Mat flat(16, 16, CV_8UC3, cv::Scalar(40, 120, 200));
    ASSERT_TRUE(cv::imwrite(path("ok.png"), flat));
    ASSERT_TRUE(cv::imwrite(path("ok.jpg"), flat));
    write_dicom("ok.dcm", std::vector<Uint16>(12, 7), 0, 0);
    const std::string png = read("ok.png"), jpg = read("ok.jpg"), dcm = read("ok.dcm");
    // The pixel data's length field says 2 GB (explicit VR: tag, "OW", 2 reserved, length).
    std::string huge = dcm;
    const std::size_t pix = huge.rfind(std::string("\xE0\x7F\x10\x00OW\0\0", 8));
    ASSERT_NE(pix, std::string::npos);
    huge.replace(pix + 8, 4, std::string("\xF0\xFF\xFF\x7F", 4));
    struct Case {
        std::string name, bytes, says;
    };
    const Case cases[] = {
        {"cut.png", png.substr(0, png.size() / 2), "truncated PNG"},
        {"cut.jpg", jpg.substr(0, jpg.size() - 10), "truncated JPEG"},
        {"cut.dcm", dcm.substr(0, dcm.size() - 9), "DICOM"},
        {"huge.dcm", huge, "DICOM"},
        {"junk.jpg", std::string(300, 'x'), "neither DICOM, PNG nor JPEG"},
        {"empty.png", "", "empty file"},
    };
    for (const Case& c : cases) {
        write(c.name, c.bytes);
        MediaImage img;
        std::string error;
        EXPECT_FALSE(load_media_image(path(c.name), img, error)) << c.name;
        EXPECT_NE(error.find(path(c.name)), std::string::npos) << error;
        EXPECT_NE(error.find(c.says), std::string::npos) << error;
        EXPECT_TRUE(img.rgba.empty());
    }
    MediaImage img;
    std::string error;
    EXPECT_FALSE(load_media_image(path("absent.png"), img, error));
    EXPECT_NE(error.find("absent.png: cannot open"), std::string::npos) << error;
}

TEST_F(MediaTest, FolderLoadsImagesInNameOrderAndReportsProblems) {
    cv::Mat flat(8, 8, CV_8UC3, cv::Scalar(1, 2, 3));
    ASSERT_TRUE(cv::imwrite(path("b_xray.png"), flat));
    write_dicom("a_ct.dcm", std::vector<Uint16>(12, 5), 0, 0);
    write_dicom("c_mri_no_extension", std::vector<Uint16>(12, 9), 0, 0);
    write("d_broken.jpg", "\xFF\xD8\xFF garbage");
    write("readme.md", "not an image");
    write("patient.txt", "name: Anna Müller\nid: 0042\nbirth_date: 1971-04-02\n");
    MediaLibrary lib;
    std::string error;
    ASSERT_TRUE(lib.load(dir_.string(), error)) << error;
    ASSERT_EQ(lib.images().size(), 3u);
    EXPECT_EQ(lib.images()[0].name, "a_ct.dcm");
    EXPECT_EQ(lib.images()[1].name, "b_xray.png");
    EXPECT_EQ(lib.images()[2].name, "c_mri_no_extension");
    ASSERT_EQ(lib.problems().size(), 1u);
    EXPECT_NE(lib.problems()[0].find("d_broken.jpg: truncated JPEG"), std::string::npos)
        << lib.problems()[0];
    ASSERT_TRUE(lib.patient().has_value());
    EXPECT_EQ(lib.patient()->name, "Anna Müller");

    fs::remove(path("patient.txt"));
    ASSERT_TRUE(lib.load(dir_.string(), error));
    EXPECT_FALSE(lib.patient().has_value());
    ASSERT_EQ(lib.problems().size(), 2u);
    EXPECT_NE(lib.problems()[1].find("patient.txt: cannot open"), std::string::npos);

    EXPECT_FALSE(lib.load(path("no_such_folder"), error));
    EXPECT_NE(error.find("no_such_folder: cannot list"), std::string::npos) << error;
}

TEST(PatientRecord, ParsesTheDocumentedKeys) {
    PatientRecord r;
    std::string error;
    ASSERT_TRUE(parse_patient_record("# record\nname: Anna Müller\nid:  0042-77 \n\n"
                                     "birth_date: 1971-04-02\nprocedure: Cholecystectomy\n"
                                     "notes: allergic to latex\nnotes: prior appendectomy\n",
                                     "p.txt", r, error))
        << error;
    EXPECT_EQ(r.name, "Anna Müller");
    EXPECT_EQ(r.id, "0042-77");
    EXPECT_EQ(r.birth_date, "1971-04-02");
    EXPECT_EQ(r.procedure, "Cholecystectomy");
    EXPECT_EQ(r.notes, "allergic to latex\nprior appendectomy");
}

TEST(PatientRecord, ErrorsNameFileAndLine) {
    struct Case {
        const char* text;
        const char* says;
    };
    const Case cases[] = {
        {"name: A\nid: 1\nweight: 70\n", "p.txt:3: unknown key 'weight'"},
        {"name: A\nid 1\n", "p.txt:2: expected 'key: value'"},
        {"name: A\nid: 1\nbirth_date: 02.04.1971\n", "p.txt:3: birth_date '02.04.1971' is not YYYY-MM-DD"},
        {"name: A\nname: B\nid: 1\n", "p.txt:2: 'name' given twice"},
        {"name: A\n", "p.txt: missing id"},
        {"id: 1\n", "p.txt: missing name"},
    };
    for (const Case& c : cases) {
        PatientRecord r;
        std::string error;
        EXPECT_FALSE(parse_patient_record(c.text, "p.txt", r, error)) << c.text;
        EXPECT_EQ(error.rfind(c.says, 0), 0u) << error;
    }
    PatientRecord r;
    std::string error;
    EXPECT_FALSE(parse_patient_record("name: " + std::string(300, 'a') + "\nid: 1\n", "p.txt", r, error));
    EXPECT_NE(error.find("p.txt:1: value of 'name' longer than 200 bytes"), std::string::npos) << error;
}

}  // namespace
}  // namespace endotower::media
