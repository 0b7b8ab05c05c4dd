// materials.pov - dqjulia fractals in materials the core's renderer cannot draw: glass that
// refracts, polished metal that reflects, and glowing media filling a fractal's volume.
//
//   left    glass:  the paper's high-detail constant c = (-0.39054, -0.58679, 0, 0)(0, 0.5632, 0, 0.05),
//                   "paper", N = 12: refraction (ior 1.5), fresnel reflection, tinted absorption
//   middle  copper: the paper's test2 tile 2, c = (-0.67, -0.54, -0.07, 0.02)(0.06, -0.53, 0.15, -0.27),
//                   "paper", N = 8: metallic reflection
//   right   media:  the paper's first constant c = (-0.10, 0.8, -0.26, 0.15)(-0.23, -0.38, -0.86, 0.64)
//                   under the true algebra "dual", N = 12 (under "paper" its slice is empty): a thin
//                   shell of glass filled with emitting media whose density follows the orbit trap
//
// Render from this folder (dqjulia.inc is in ../../povray):
//   povray +L../../povray +W960 +H400 +A0.3 materials.pov

#version 3.7;
global_settings { assumed_gamma 1.0 max_trace_level 12 }

#include "dqjulia.inc"

#declare Slice = DQJ_Slice_Names("a.s,a.i,a.j");
#declare High_Detail = array[8] {-0.39054, -0.58679, 0, 0,  0, 0.5632, 0, 0.05};
#declare Test2_Tile2 = array[8] {-0.67, -0.54, -0.07, 0.02,  0.06, -0.53, 0.15, -0.27};
#declare First = array[8] {-0.10, 0.8, -0.26, 0.15,  -0.23, -0.38, -0.86, 0.64};

// About two pixels at the objects' distance on a 400-pixel-high image: glass and
// metal show every ripple of the surface, a slightly smoother one reads better.
#declare Threshold = 4 * 9.5 * tan(radians(22)) / 400;

camera {
  location <0, 2.6, -9.5>
  look_at <0, 0.1, 0>
  angle 58
  right x * image_width / image_height
}

light_source { <-5, 9, -7> color rgb <1, 0.97, 0.92> }
light_source { <7, 5, -4> color rgb <0.35, 0.4, 0.5> shadowless }

sky_sphere {
  pigment { gradient y color_map { [0 rgb <0.5, 0.52, 0.56>] [0.5 rgb <0.2, 0.25, 0.35>] [1 rgb <0.05, 0.07, 0.12>] } }
}

plane {
  y, -1.05
  texture {
    pigment { checker rgb <0.3, 0.3, 0.31> rgb <0.22, 0.22, 0.23> scale 0.6 }
    finish { diffuse 0.8 reflection 0.08 }
  }
}

// Glass.
object {
  DQJ_Isosurface(High_Detail, "paper", 12, 4, Slice, Threshold)
  material {
    texture {
      pigment { rgbf <0.96, 0.99, 1, 0.96> }
      finish { ambient 0 diffuse 0.05 specular 0.9 roughness 0.001 reflection { 0.04, 1 fresnel } conserve_energy }
    }
    interior { ior 1.5 fade_distance 1.2 fade_power 1001 fade_color <0.55, 0.8, 0.85> }
  }
  rotate y * 20
  translate x * -3.3
}

// Copper.
object {
  DQJ_Isosurface(Test2_Tile2, "paper", 8, 4, Slice, Threshold)
  texture {
    pigment { rgb <0.95, 0.55, 0.35> }
    finish { ambient 0 diffuse 0.3 brilliance 3 specular 0.9 roughness 0.006 metallic reflection { 0.55 metallic } }
  }
  rotate y * -15
}

// Media: emission inside the set, brighter where the orbit comes close to 0.
#declare Glow_Trap = DQJ_Coloring_Function(First, "dual", 12, 4, Slice, "trap");
object {
  DQJ_Isosurface(First, "dual", 12, 4, Slice, Threshold)
  hollow
  material {
    texture {
      pigment { rgbt <1, 1, 1, 1> }
      finish { ambient 0 diffuse 0 specular 0.6 roughness 0.005 reflection { 0.02, 0.4 fresnel } }
    }
    interior {
      ior 1.05
      media {
        emission rgb <1.0, 0.45, 0.15> * 1.6
        intervals 1 samples 6 method 3
        density {
          function { Glow_Trap(x, y, z) }
          color_map { [0 rgb 1.2] [0.35 rgb 0.5] [0.6 rgb 0.05] [1 rgb 0] }
        }
      }
    }
  }
  rotate y * -30
  translate x * 3.3
}
