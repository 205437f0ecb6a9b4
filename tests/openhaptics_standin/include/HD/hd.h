//! @file
//! Stand-in for the OpenHaptics HD API header <HD/hd.h>, so CI can compile and test the Geomagic
//! Touch adapter without the proprietary SDK. Names, types, constant values and signatures follow
//! the public OpenHaptics 3.4 HD API reference, limited to what the adapter uses (plus the full
//! error-code list). The simulated device behind it is driven by <hd_standin_control.hpp>.
#ifndef ENDOHAPTICS_HD_STANDIN_HD_H
#define ENDOHAPTICS_HD_STANDIN_HD_H

#include <limits.h>
#include <stddef.h>

//! Defined only by the stand-in: tests check they are not compiled against the real SDK.
#define ENDOHAPTICS_HD_STANDIN 1

// Calling conventions: empty on Linux in the SDK too (__stdcall on Windows).
#define HDAPI
#define HDAPIENTRY
#define HDCALLBACK

#ifdef __cplusplus
extern "C" {
#endif

// ---- Types (hdDefines.h) ------------------------------------------------------------------------
typedef unsigned int HDuint;
typedef unsigned char HDboolean;
typedef unsigned long HDulong;
typedef unsigned short HDushort;
typedef int HDint;
typedef float HDfloat;
typedef double HDdouble;
typedef long HDlong;
typedef char HDchar;
typedef unsigned int HDerror;
typedef unsigned int HDenum;
typedef const char* HDstring;
typedef unsigned int HHD;  //!< device handle

//! What hdGetError returns: the HD code, the driver's own code, the device it concerns.
typedef struct {
  HDerror errorCode;      //!< one of the HD_* codes below; HD_SUCCESS when the stack is empty
  int internalErrorCode;  //!< the device driver's own error code
  HHD hHD;                //!< the current device when the error occurred
} HDErrorInfo;

#define HD_TRUE 1
#define HD_FALSE 0

// ---- Error codes --------------------------------------------------------------------------------
#define HD_SUCCESS 0x0000
// Function errors
#define HD_INVALID_ENUM 0x0100
#define HD_INVALID_VALUE 0x0101
#define HD_INVALID_OPERATION 0x0102
#define HD_INVALID_INPUT_TYPE 0x0103
#define HD_BAD_HANDLE 0x0104
// Force errors
#define HD_WARM_MOTORS 0x0200
#define HD_EXCEEDED_MAX_FORCE 0x0201
#define HD_EXCEEDED_MAX_FORCE_IMPULSE 0x0202
#define HD_EXCEEDED_MAX_VELOCITY 0x0203
#define HD_FORCE_ERROR 0x0204
// Device errors
#define HD_DEVICE_FAULT 0x0300
#define HD_DEVICE_ALREADY_INITIATED 0x0301
#define HD_COMM_ERROR 0x0302
#define HD_COMM_CONFIG_ERROR 0x0303
#define HD_TIMER_ERROR 0x0304
// Haptic rendering context
#define HD_ILLEGAL_BEGIN 0x0400
#define HD_ILLEGAL_END 0x0401
#define HD_FRAME_ERROR 0x0402
// Scheduler errors
#define HD_INVALID_PRIORITY 0x0500
#define HD_SCHEDULER_FULL 0x0501
// Licensing errors
#define HD_INVALID_LICENSE 0x0600

//! True when an HDErrorInfo holds an error.
#define HD_DEVICE_ERROR(X) (((X).errorCode) != HD_SUCCESS)

// ---- Parameters (hdGet*/hdSet*) -----------------------------------------------------------------
#define HD_CURRENT_BUTTONS 0x2000    //!< HDint, bit i: button i+1 pressed
#define HD_CURRENT_POSITION 0x2050   //!< 3 HDdouble, mm, device frame (x right, y up, z to user)
#define HD_CALIBRATION_STYLE 0x2555  //!< HDint, HD_CALIBRATION_* style bits the device supports
#define HD_CURRENT_FORCE 0x2700      //!< 3 HDdouble, N, device frame

// ---- Capabilities (hdEnable/hdDisable) ----------------------------------------------------------
#define HD_FORCE_OUTPUT 0x4000
#define HD_MAX_FORCE_CLAMPING 0x4001
#define HD_FORCE_RAMPING 0x4002
#define HD_SOFTWARE_FORCE_LIMIT 0x4003
#define HD_ONE_FRAME_LIMIT 0x4004

// ---- Miscellaneous ------------------------------------------------------------------------------
#define HD_MAX_SCHEDULER_PRIORITY USHRT_MAX
#define HD_MIN_SCHEDULER_PRIORITY 0
#define HD_DEFAULT_SCHEDULER_PRIORITY ((HD_MAX_SCHEDULER_PRIORITY + HD_MIN_SCHEDULER_PRIORITY) / 2)

// Calibration status (hdCheckCalibration)
#define HD_CALIBRATION_OK 0x5000
#define HD_CALIBRATION_NEEDS_UPDATE 0x5001
#define HD_CALIBRATION_NEEDS_MANUAL_INPUT 0x5002
// Calibration styles (HD_CALIBRATION_STYLE, hdUpdateCalibration)
#define HD_CALIBRATION_ENCODER_RESET (1 << 0)
#define HD_CALIBRATION_AUTO (1 << 1)
#define HD_CALIBRATION_INKWELL (1 << 2)

// Button masks
#define HD_DEVICE_BUTTON_1 (1 << 0)
#define HD_DEVICE_BUTTON_2 (1 << 1)
#define HD_DEVICE_BUTTON_3 (1 << 2)
#define HD_DEVICE_BUTTON_4 (1 << 3)

#define HD_INVALID_HANDLE 0xFFFFFFFF
#define HD_DEFAULT_DEVICE NULL

// ---- Device routines (hdDevice.h) ---------------------------------------------------------------
HDAPI HHD HDAPIENTRY hdInitDevice(HDstring pConfigName);
HDAPI void HDAPIENTRY hdDisableDevice(HHD hHD);
HDAPI void HDAPIENTRY hdBeginFrame(HHD hHD);
HDAPI void HDAPIENTRY hdEndFrame(HHD hHD);
HDAPI HDErrorInfo HDAPIENTRY hdGetError(void);
HDAPI HDstring HDAPIENTRY hdGetErrorString(HDerror errorCode);
HDAPI void HDAPIENTRY hdEnable(HDenum cap);
HDAPI void HDAPIENTRY hdDisable(HDenum cap);
HDAPI void HDAPIENTRY hdGetIntegerv(HDenum pname, HDint* params);
HDAPI void HDAPIENTRY hdGetDoublev(HDenum pname, HDdouble* params);
HDAPI void HDAPIENTRY hdSetDoublev(HDenum pname, const HDdouble* params);
HDAPI HDenum HDAPIENTRY hdCheckCalibration(void);
HDAPI void HDAPIENTRY hdUpdateCalibration(HDenum style);

// ---- Scheduler (hdScheduler.h) ------------------------------------------------------------------
typedef unsigned int HDCallbackCode;
#define HD_CALLBACK_DONE 0
#define HD_CALLBACK_CONTINUE 1

typedef unsigned long HDSchedulerHandle;
typedef HDCallbackCode(HDCALLBACK* HDSchedulerCallback)(void* pUserData);

HDAPI void HDAPIENTRY hdStartScheduler(void);
HDAPI void HDAPIENTRY hdStopScheduler(void);
HDAPI void HDAPIENTRY hdScheduleSynchronous(HDSchedulerCallback pCallback, void* pUserData,
                                            HDushort nPriority);
HDAPI HDSchedulerHandle HDAPIENTRY hdScheduleAsynchronous(HDSchedulerCallback pCallback,
                                                          void* pUserData, HDushort nPriority);
HDAPI void HDAPIENTRY hdUnschedule(HDSchedulerHandle hHandle);

#ifdef __cplusplus
}
#endif

#endif  // ENDOHAPTICS_HD_STANDIN_HD_H
