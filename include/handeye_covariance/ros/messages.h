// The package's generated messages and services, named in namespace handeye.
#pragma once

#include "handeye_covariance/AutoCalibrateAction.h"
#include "handeye_covariance/Calibrate.h"
#include "handeye_covariance/CalibrationCheck.h"
#include "handeye_covariance/CheckCalibration.h"
#include "handeye_covariance/CalibrationStatus.h"
#include "handeye_covariance/ListSamples.h"
#include "handeye_covariance/LoadSamples.h"
#include "handeye_covariance/RemoveSample.h"
#include "handeye_covariance/Reset.h"
#include "handeye_covariance/SaveCalibration.h"
#include "handeye_covariance/SaveSamples.h"
#include "handeye_covariance/SuggestPose.h"
#include "handeye_covariance/TagDetection.h"
#include "handeye_covariance/TagDetectionArray.h"
#include "handeye_covariance/TakeSample.h"

namespace handeye {
using handeye_covariance::AutoCalibrateAction;
using handeye_covariance::AutoCalibrateFeedback;
using handeye_covariance::AutoCalibrateGoal;
using handeye_covariance::AutoCalibrateResult;
using handeye_covariance::Calibrate;
using handeye_covariance::CalibrationStatus;
using handeye_covariance::CheckCalibration;
using CalibrationCheckMsg = handeye_covariance::CalibrationCheck;
using handeye_covariance::ListSamples;
using handeye_covariance::LoadSamples;
using handeye_covariance::RemoveSample;
using handeye_covariance::Reset;
using handeye_covariance::SaveCalibration;
using handeye_covariance::SaveSamples;
using handeye_covariance::SuggestPose;
using handeye_covariance::TagDetection;
using handeye_covariance::TagDetectionArray;
using handeye_covariance::TakeSample;
}  // namespace handeye
