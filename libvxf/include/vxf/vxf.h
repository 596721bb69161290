// vxf — the umbrella header: the whole public API of libvxf (link vxf::vxf). OpenVDB's heavy
// tools (meshToVolume, filters) stay in the library's sources, so this compiles as OpenVDB's
// grids and CGAL-free headers do. The voxel editor's server (<vxf/view/...>) is not part of it.
#pragma once

#include <vxf/core/Error.h>
#include <vxf/core/GridRoles.h>
#include <vxf/core/GridStats.h>
#include <vxf/core/Interrupter.h>
#include <vxf/core/MemoryBudget.h>
#include <vxf/core/ProceduralMesh.h>
#include <vxf/core/RenderedImage.h>
#include <vxf/core/Scene.h>
#include <vxf/core/TriangleMesh.h>
#include <vxf/core/VoxelSet.h>
#include <vxf/io/ImageFile.h>
#include <vxf/io/MeshFile.h>
#include <vxf/io/MitsubaVolume.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/io/VxfText.h>
#include <vxf/light/DirectLight.h>
#include <vxf/ops/Registry.h>
#include <vxf/pipeline/Graph.h>
#include <vxf/pipeline/LightScene.h>
#include <vxf/pipeline/Operators.h>
#include <vxf/pipeline/RunPipeline.h>
#include <vxf/pipeline/SceneFile.h>
#include <vxf/render/Render.h>
#include <vxf/scatter/Scatter.h>
#include <vxf/transport/Medium.h>
#include <vxf/voxelize/Voxelize.h>
