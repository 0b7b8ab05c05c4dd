// paper-highres.pov - the paper's "High-Detail" figure, written by hand with dqjulia.inc.
//
// c = (-0.39054, -0.58679, 0, 0)(0, 0.5632, 0, 0.05), variant "paper", N = 15, the slice
// a.s, a.i, a.j through 0 (examples/paper-highres.json): the quaternion Julia set of the
// Siegel-disk constant, in a glazed ceramic coloured by the orbit trap, on a tiled floor
// under a soft light.
//
// Render from this folder (dqjulia.inc is in ../../povray):
//   povray +L../../povray +W800 +H600 +A0.3 paper-highres.pov

#version 3.7;
global_settings { assumed_gamma 1.0 }

#include "dqjulia.inc"

#declare C = array[8] {-0.39054, -0.58679, 0, 0,  0, 0.5632, 0, 0.05};
#declare Variant = "paper";
#declare N = 15;
#declare R = 4;
#declare Slice = DQJ_Slice_Names("a.s,a.i,a.j");

// The surface is drawn where the distance estimate is about one pixel at this view.
#declare Threshold = 2 * 4.8 * tan(radians(20)) / image_height;

camera {
  location <0.55, 0.75, -1> * 4.1
  look_at <0, -0.15, 0>
  angle 50
  right x * image_width / image_height
}

light_source {
  <4, 9, -5> color rgb <1, 0.96, 0.9> * 1.1
  area_light <1.2, 0, 0>, <0, 0, 1.2>, 3, 3 adaptive 1 circular orient
}
light_source { <-6, 3, 4> color rgb <0.35, 0.42, 0.6> shadowless }

sky_sphere {
  pigment { gradient y color_map { [0 rgb <0.25, 0.27, 0.32>] [1 rgb <0.55, 0.62, 0.75>] } }
}

plane {
  y, -1.0
  texture {
    pigment { checker rgb <0.42, 0.41, 0.39> rgb <0.36, 0.35, 0.33> scale 0.5 }
    finish { diffuse 0.8 specular 0.15 roughness 0.02 reflection 0.05 }
  }
}

// The orbit trap (smallest |a| along the orbit), scaled to [0, 1] as the core's "trap" colouring.
#declare Trap = DQJ_Coloring_Function(C, Variant, N, R, Slice, "trap");

object {
  DQJ_Isosurface(C, Variant, N, R, Slice, Threshold)
  texture {
    pigment {
      function { Trap(x, y, z) }
      color_map { [0 rgb <0.95, 0.75, 0.40>] [0.5 rgb <0.80, 0.30, 0.20>] [1 rgb <0.20, 0.25, 0.55>] }
    }
    finish { ambient 0.03 diffuse 0.75 specular 0.5 roughness 0.01 reflection { 0.02, 0.2 fresnel } }
  }
  interior { ior 1.5 }
}
