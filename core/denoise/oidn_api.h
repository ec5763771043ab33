// The part of Intel Open Image Denoise's C API (2.x) that oidn_denoiser.cpp
// calls, declared from the library's API documentation. The official build
// gdvr installs (the PyPI wheel pyoidn; deploy/install-deps.sh) ships the
// shared library and its CMake package but not <OpenImageDenoise/oidn.h>.
// Enumerator values are the ABI's; only what is used is declared.
#pragma once

#include <cstddef>

extern "C" {

typedef struct OIDNDeviceImpl* OIDNDevice;
typedef struct OIDNFilterImpl* OIDNFilter;

typedef enum {
  OIDN_DEVICE_TYPE_DEFAULT = 0,
  OIDN_DEVICE_TYPE_CPU = 1,
} OIDNDeviceType;

typedef enum {
  OIDN_ERROR_NONE = 0,
} OIDNError;

typedef enum {
  OIDN_FORMAT_UNDEFINED = 0,
  OIDN_FORMAT_FLOAT = 1,
  OIDN_FORMAT_FLOAT2 = 2,
  OIDN_FORMAT_FLOAT3 = 3,
} OIDNFormat;

typedef enum {
  OIDN_QUALITY_DEFAULT = 0,
  OIDN_QUALITY_BALANCED = 5,
  OIDN_QUALITY_HIGH = 6,
} OIDNQuality;

OIDNDevice oidnNewDevice(OIDNDeviceType type);
void oidnSetDeviceBool(OIDNDevice device, const char* name, bool value);
void oidnSetDeviceInt(OIDNDevice device, const char* name, int value);
void oidnCommitDevice(OIDNDevice device);
OIDNError oidnGetDeviceError(OIDNDevice device, const char** outMessage);
void oidnReleaseDevice(OIDNDevice device);

OIDNFilter oidnNewFilter(OIDNDevice device, const char* type);
void oidnSetSharedFilterImage(OIDNFilter filter, const char* name, void* devPtr, OIDNFormat format, size_t width,
                              size_t height, size_t byteOffset, size_t pixelByteStride, size_t rowByteStride);
void oidnSetFilterBool(OIDNFilter filter, const char* name, bool value);
void oidnSetFilterInt(OIDNFilter filter, const char* name, int value);
void oidnCommitFilter(OIDNFilter filter);
void oidnExecuteFilter(OIDNFilter filter);
void oidnReleaseFilter(OIDNFilter filter);

}  // extern "C"
