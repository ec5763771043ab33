#include "core/scene/spectrum_to_rgb.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace gdvr {
namespace {

// CIE 1931 2-degree colour-matching functions x, y, z and the relative
// spectral power of illuminant D65 (100 at 560 nm), every 5 nm from 360 to
// 830 nm (CIE 015:2018 tables; ISO/CIE 11664-1 and -2).
constexpr double kFirstWavelength = 360.0, kLastWavelength = 830.0, kTableStep = 5.0;
struct CieSample {
  double x, y, z, d65;
};
constexpr CieSample kCie[] = {
    {0.0001299, 3.917e-06, 0.0006061, 46.6383},  // 360
    {0.0002321, 6.965e-06, 0.001086, 49.3637},  // 365
    {0.0004149, 1.239e-05, 0.001946, 52.0891},  // 370
    {0.0007416, 2.202e-05, 0.003486, 51.0323},  // 375
    {0.001368, 3.9e-05, 0.006450001, 49.9755},  // 380
    {0.002236, 6.4e-05, 0.01054999, 52.3118},  // 385
    {0.004243, 0.00012, 0.02005001, 54.6482},  // 390
    {0.00765, 0.000217, 0.03621, 68.7015},  // 395
    {0.01431, 0.000396, 0.06785001, 82.7549},  // 400
    {0.02319, 0.00064, 0.1102, 87.1204},  // 405
    {0.04351, 0.00121, 0.2074, 91.4860},  // 410
    {0.07763, 0.00218, 0.3713, 92.4589},  // 415
    {0.13438, 0.004, 0.6456, 93.4318},  // 420
    {0.21477, 0.0073, 1.03905, 90.0570},  // 425
    {0.2839, 0.0116, 1.3856, 86.6823},  // 430
    {0.3285, 0.01684, 1.62296, 95.7736},  // 435
    {0.34828, 0.023, 1.74706, 104.8650},  // 440
    {0.34806, 0.0298, 1.7826, 110.9360},  // 445
    {0.3362, 0.038, 1.77211, 117.0080},  // 450
    {0.3187, 0.048, 1.7441, 117.4100},  // 455
    {0.2908, 0.06, 1.6692, 117.8120},  // 460
    {0.2511, 0.0739, 1.5281, 116.3360},  // 465
    {0.19536, 0.09098, 1.28764, 114.8610},  // 470
    {0.1421, 0.1126, 1.0419, 115.3920},  // 475
    {0.09564, 0.13902, 0.8129501, 115.9230},  // 480
    {0.05795001, 0.1693, 0.6162, 112.3670},  // 485
    {0.03201, 0.20802, 0.46518, 108.8110},  // 490
    {0.0147, 0.2586, 0.3533, 109.0820},  // 495
    {0.0049, 0.323, 0.272, 109.3540},  // 500
    {0.0024, 0.4073, 0.2123, 108.5780},  // 505
    {0.0093, 0.503, 0.1582, 107.8020},  // 510
    {0.0291, 0.6082, 0.1117, 106.2960},  // 515
    {0.06327, 0.71, 0.07824999, 104.7900},  // 520
    {0.1096, 0.7932, 0.05725001, 106.2390},  // 525
    {0.1655, 0.862, 0.04216, 107.6890},  // 530
    {0.2257499, 0.9148501, 0.02984, 106.0470},  // 535
    {0.2904, 0.954, 0.0203, 104.4050},  // 540
    {0.3597, 0.9803, 0.0134, 104.2250},  // 545
    {0.4334499, 0.9949501, 0.008749999, 104.0460},  // 550
    {0.5120501, 1, 0.005749999, 102.0230},  // 555
    {0.5945, 0.995, 0.0039, 100.0000},  // 560
    {0.6784, 0.9786, 0.002749999, 98.1671},  // 565
    {0.7621, 0.952, 0.0021, 96.3342},  // 570
    {0.8425, 0.9154, 0.0018, 96.0611},  // 575
    {0.9163, 0.87, 0.001650001, 95.7880},  // 580
    {0.9786, 0.8163, 0.0014, 92.2368},  // 585
    {1.0263, 0.757, 0.0011, 88.6856},  // 590
    {1.0567, 0.6949, 0.001, 89.3459},  // 595
    {1.0622, 0.631, 0.0008, 90.0062},  // 600
    {1.0456, 0.5668, 0.0006, 89.8026},  // 605
    {1.0026, 0.503, 0.00034, 89.5991},  // 610
    {0.9384, 0.4412, 0.00024, 88.6489},  // 615
    {0.8544499, 0.381, 0.00019, 87.6987},  // 620
    {0.7514, 0.321, 0.0001, 85.4936},  // 625
    {0.6424, 0.265, 4.999999e-05, 83.2886},  // 630
    {0.5419, 0.217, 3e-05, 83.4939},  // 635
    {0.4479, 0.175, 2e-05, 83.6992},  // 640
    {0.3608, 0.1382, 1e-05, 81.8630},  // 645
    {0.2835, 0.107, 0, 80.0268},  // 650
    {0.2187, 0.0816, 0, 80.1207},  // 655
    {0.1649, 0.061, 0, 80.2146},  // 660
    {0.1212, 0.04458, 0, 81.2462},  // 665
    {0.0874, 0.032, 0, 82.2778},  // 670
    {0.0636, 0.0232, 0, 80.2810},  // 675
    {0.04677, 0.017, 0, 78.2842},  // 680
    {0.0329, 0.01192, 0, 74.0027},  // 685
    {0.0227, 0.00821, 0, 69.7213},  // 690
    {0.01584, 0.005723, 0, 70.6652},  // 695
    {0.01135916, 0.004102, 0, 71.6091},  // 700
    {0.008110916, 0.002929, 0, 72.9790},  // 705
    {0.005790346, 0.002091, 0, 74.3490},  // 710
    {0.004109457, 0.001484, 0, 67.9765},  // 715
    {0.002899327, 0.001047, 0, 61.6040},  // 720
    {0.00204919, 0.00074, 0, 65.7448},  // 725
    {0.001439971, 0.00052, 0, 69.8856},  // 730
    {0.0009999493, 0.0003611, 0, 72.4863},  // 735
    {0.0006900786, 0.0002492, 0, 75.0870},  // 740
    {0.0004760213, 0.0001719, 0, 69.3398},  // 745
    {0.0003323011, 0.00012, 0, 63.5927},  // 750
    {0.0002348261, 8.48e-05, 0, 55.0054},  // 755
    {0.0001661505, 6e-05, 0, 46.4182},  // 760
    {0.000117413, 4.24e-05, 0, 56.6118},  // 765
    {8.307527e-05, 3e-05, 0, 66.8054},  // 770
    {5.870652e-05, 2.12e-05, 0, 65.0941},  // 775
    {4.150994e-05, 1.499e-05, 0, 63.3828},  // 780
    {2.935326e-05, 1.06e-05, 0, 63.8434},  // 785
    {2.067383e-05, 7.4657e-06, 0, 64.3040},  // 790
    {1.455977e-05, 5.2578e-06, 0, 61.8779},  // 795
    {1.025398e-05, 3.7029e-06, 0, 59.4519},  // 800
    {7.221456e-06, 2.6078e-06, 0, 55.7054},  // 805
    {5.085868e-06, 1.8366e-06, 0, 51.9590},  // 810
    {3.581652e-06, 1.2934e-06, 0, 54.6998},  // 815
    {2.522525e-06, 9.1093e-07, 0, 57.4406},  // 820
    {1.776509e-06, 6.4153e-07, 0, 58.8765},  // 825
    {1.251141e-06, 4.5181e-07, 0, 60.3125},  // 830
};
constexpr int kCieSamples = int(sizeof(kCie) / sizeof(kCie[0]));
static_assert(kCieSamples == 95);

// Mitsuba's normalisations (core/spectrum.h): 1 / integral of y over
// 360-830 nm, and D65's scale in its tables. With them an equal-energy
// spectrum of 1 has Y = 1, and a flat reflectance of 1 under D65 is white.
constexpr double kCieYNormalization = 0.009367658735689113;  // 1 / 106.75026
constexpr double kD65Normalization = 0.010101273599490354;

CieSample cie_at(double wavelength) {
  const double x = (wavelength - kFirstWavelength) / kTableStep;
  const int i = std::clamp(int(x), 0, kCieSamples - 2);
  const double t = std::clamp(x - double(i), 0.0, 1.0);
  const CieSample& a = kCie[i];
  const CieSample& b = kCie[i + 1];
  return {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.z + t * (b.z - a.z), a.d65 + t * (b.d65 - a.d65)};
}

// CIE XYZ to linear sRGB (D65 white), the matrix Mitsuba uses.
Rgb xyz_to_linear_srgb(double X, double Y, double Z) {
  return Rgb(float(3.240479 * X - 1.537150 * Y - 0.498535 * Z), float(-0.969256 * X + 1.875991 * Y + 0.041556 * Z),
             float(0.055648 * X - 0.204043 * Y + 1.057311 * Z));
}

}  // namespace

SpectrumRole spectrum_role(const std::string& name, bool within_emitter) {
  if (within_emitter) return SpectrumRole::kEmission;
  if (name == "eta" || name == "k" || name == "int_ior" || name == "ext_ior") return SpectrumRole::kUnbounded;
  return SpectrumRole::kReflectance;
}

Rgb constant_spectrum_to_rgb(float value, SpectrumRole role) {
  return role == SpectrumRole::kEmission ? xyz_to_linear_srgb(value, value, value) : Rgb(value);
}

Expected<Rgb> spectrum_list_to_rgb(const std::vector<double>& wavelengths, const std::vector<double>& values,
                                   SpectrumRole role) {
  if (wavelengths.size() != values.size()) return invalid_argument("spectrum: as many wavelengths as values needed");
  if (wavelengths.size() < 2) return invalid_argument("spectrum: at least two wavelength:value pairs needed");
  for (size_t i = 0; i < wavelengths.size(); ++i) {
    if (!std::isfinite(wavelengths[i]) || !std::isfinite(values[i]))
      return invalid_argument("spectrum: non-finite wavelength or value");
    if (i > 0 && !(wavelengths[i] > wavelengths[i - 1]))
      return invalid_argument("spectrum: wavelengths must increase (" + std::to_string(wavelengths[i - 1]) +
                              " then " + std::to_string(wavelengths[i]) + ")");
  }
  // Mitsuba's quadrature: 1000 points spread over [360, 830] nm with both
  // ends included, each weighted by (830 - 360) / 1000.
  constexpr int kSteps = 1000;
  const bool under_d65 = role != SpectrumRole::kEmission;
  double X = 0, Y = 0, Z = 0;
  size_t k = 0;
  for (int i = 0; i < kSteps; ++i) {
    const double w = kFirstWavelength + (double(i) / (kSteps - 1)) * (kLastWavelength - kFirstWavelength);
    if (w < wavelengths.front() || w > wavelengths.back()) continue;
    while (k + 2 < wavelengths.size() && wavelengths[k + 1] <= w) ++k;
    const double t = (w - wavelengths[k]) / (wavelengths[k + 1] - wavelengths[k]);
    const double v = (values[k] + t * (values[k + 1] - values[k])) * kCieYNormalization;
    const CieSample c = cie_at(w);
    const double s = v * (under_d65 ? c.d65 * kD65Normalization : 1.0);
    X += c.x * s;
    Y += c.y * s;
    Z += c.z * s;
  }
  const double dw = (kLastWavelength - kFirstWavelength) / kSteps;
  Rgb rgb = xyz_to_linear_srgb(X * dw, Y * dw, Z * dw);
  const float hi = role == SpectrumRole::kReflectance ? 1.0f : INFINITY;
  rgb = Rgb(std::clamp(rgb.r, 0.0f, hi), std::clamp(rgb.g, 0.0f, hi), std::clamp(rgb.b, 0.0f, hi));
  return rgb;
}

Status parse_spd(const std::string& text, const std::string& name, std::vector<double>* wavelengths,
                 std::vector<double>* values) {
  std::istringstream in(text);
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream fields(line);
    double w, v;
    if (!(fields >> w)) {
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;  // blank
      return invalid_argument(name + ":" + std::to_string(line_number) + ": expected 'wavelength value'");
    }
    std::string rest;
    if (!(fields >> v) || (fields >> rest))
      return invalid_argument(name + ":" + std::to_string(line_number) + ": expected 'wavelength value'");
    wavelengths->push_back(w);
    values->push_back(v);
  }
  if (wavelengths->size() < 2) return invalid_argument(name + ": a spectrum needs at least two lines");
  return Status::Ok();
}

}  // namespace gdvr
