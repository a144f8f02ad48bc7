#pragma once

namespace gpucol {

/// True once any part of gpucol (the broad phase or the mesh pipeline) has set up an OpenCL device in this
/// process. OpenCL starts only when a batch or a broad phase step wants it (Backend::OpenCL, or Backend::Auto
/// measuring or using a GPU); a program that never asks keeps it false and never loads the ICD loader's
/// devices.
bool openClStarted();

}  // namespace gpucol
