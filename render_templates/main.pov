// papersim scenegen: one scene for every pass. The pass is chosen by Declare=SG_PASS=<n> in the
// pass's .ini; scene.inc (generated per sample) holds the camera, lights, background and paper
// draws, sheet.inc the sheet as a mesh2 with exact material UV and normals.
#version 3.7;
#include "passes.inc"
#include "scene.inc"
#include "sheet.inc"
#include "paper.inc"
#include "backgrounds.inc"
#include "lights.inc"

#declare SG_Shading = (SG_PASS = SG_PASS_SHADING);
#declare SG_Photo = (SG_PASS = SG_PASS_IMAGE);
#declare SG_Lit = (SG_Photo | SG_Shading);

global_settings {
  assumed_gamma 1.0
  max_trace_level 6
  #if (SG_Lit & SG_Radiosity)
    radiosity {
      pretrace_start 0.08 pretrace_end SG_Radiosity_Pretrace_End count SG_Radiosity_Count
      nearest_count SG_Radiosity_Nearest
      error_bound SG_Radiosity_Error recursion_limit 1 low_error_factor 0.5
      gray_threshold 0 brightness 1 adc_bailout 0.01 / 2 normal on }
  #end
}

camera { perspective location SG_Cam_Location direction SG_Cam_Direction
         right SG_Cam_Right up SG_Cam_Up }

#if (SG_Lit)
  background { rgb SG_Light_Colour * SG_Sky * SG_Photo }
  #if (SG_Shading & SG_Radiosity)
    // Light from the environment without seeing it: a sky sphere is seen by radiosity rays only.
    sphere { 0, 50 hollow no_image texture { pigment { rgb SG_Light_Colour * SG_Sky }
             finish { emission 1 diffuse 0 ambient 0 } } }
  #end
  SG_Lights()
  SG_Background(SG_Shading)
  // The seen sheet casts no shadow; its copy behind the printed side (shadow.inc) casts them
  // unseen, so the facets of the mesh do not shadow each other where light grazes them.
  #include "shadow.inc"
  #if (SG_Shadow_Caster)
    object { SG_Sheet_Mesh SG_Paper_Texture(SG_Shading) no_shadow }
    object { SG_Sheet_Shadow_Mesh pigment { rgb 0 } no_image no_reflection no_radiosity }
  #else
    object { SG_Sheet_Mesh SG_Paper_Texture(SG_Shading) }
  #end
#else
  background { rgb 0 }
  #switch (SG_PASS)
    #case (SG_PASS_ALBEDO) object { SG_Sheet_Mesh SG_Albedo_Texture() } #break
    #case (SG_PASS_UV) object { SG_Sheet_Mesh SG_UV_Texture() } #break
    #case (SG_PASS_UV_FINE) object { SG_Sheet_Mesh SG_UV_Fine_Texture() } #break
    #case (SG_PASS_COORDS) object { SG_Sheet_Mesh SG_Coords_Texture(0) } #break
    #case (SG_PASS_COORDS_FINE) object { SG_Sheet_Mesh SG_Coords_Texture(1) } #break
    #case (SG_PASS_NORMAL) object { SG_Sheet_Mesh SG_Normal_Texture() } #break
  #end
#end
