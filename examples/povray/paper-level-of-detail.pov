// paper-level-of-detail.pov - the paper's "Level of Detail" teaser: one constant, N = 6, 8, 10, 15.
//
// c = (-0.39054, -0.58679, 0, 0)(0, 0.5632, 0, 0.05), variant "paper", slice a.s, a.i, a.j
// (examples/paper-teaser.json). At small N the distance estimate bounds the distance to the
// limit set, not to the N-iteration set, so the shape changes with N (math.md): smooth at
// N = 6, grooved by N = 15. Four isosurfaces of one include, each its own chain of N functions.
//
// Render from this folder (dqjulia.inc is in ../../povray):
//   povray +L../../povray +W1280 +H400 +A0.3 paper-level-of-detail.pov

#version 3.7;
global_settings { assumed_gamma 1.0 }

#include "dqjulia.inc"

#declare C = array[8] {-0.39054, -0.58679, 0, 0,  0, 0.5632, 0, 0.05};
#declare Slice = DQJ_Slice_Names("a.s,a.i,a.j");
#declare Levels = array[4] {6, 8, 10, 15};

camera {
  location <0, 2.2, -10.5>
  look_at <0, -0.1, 0>
  angle 62
  right x * image_width / image_height
}

light_source { <6, 12, -9> color rgb <1, 0.96, 0.9> }
light_source { <-8, 4, -2> color rgb <0.3, 0.36, 0.5> shadowless }
background { rgb <0.08, 0.09, 0.11> }

plane {
  y, -1.0
  pigment { rgb <0.3, 0.3, 0.32> }
  finish { diffuse 0.7 }
}

// About one pixel at the objects' distance on a 400-pixel-high image.
#declare Threshold = 2 * 10.5 * tan(radians(31 * 400 / 1280)) / 400;

#declare I = 0;
#while (I < 4)
  object {
    DQJ_Isosurface(C, "paper", Levels[I], 4, Slice, Threshold)
    texture {
      pigment { rgb <0.85, 0.62, 0.35> }
      finish { ambient 0.05 diffuse 0.75 phong 0.4 phong_size 30 }
    }
    rotate y * 25
    translate x * (I - 1.5) * 3.1
  }
  #declare I = I + 1;
#end
