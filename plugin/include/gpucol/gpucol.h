#pragma once

/// Everything of gpucol's public API.
#include "gpucol/collide_meshes.h"
#include "gpucol/collision_dispatcher.h"
#include "gpucol/config.h"
#include "gpucol/grid_broadphase.h"
#include "gpucol/mass_properties.h"
#include "gpucol/mesh_error.h"
#include "gpucol/mesh_mesh_algorithm.h"
#include "gpucol/mesh_report.h"
#include "gpucol/mesh_shape.h"
#include "gpucol/opencl_status.h"
#include "gpucol/principal_mesh_body.h"
#include "gpucol/triangle_mesh.h"
#include "gpucol/world_importer.h"
