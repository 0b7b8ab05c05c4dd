// paper-test2.pov - the paper's "test2" figure: six random constants, variant "paper",
// coloured by the orbit trap (examples/paper-test2-1.json ... paper-test2-6.json).
//
// Tile 1's dual part lies outside the Mandelbrot set: with b fixed at 0 the slice is empty
// for N >= 6 under the paper's rule (math.md; `dqjulia inspect` says why), so it is drawn
// at N = 5. Tile 5 is empty from N = 8 and is drawn at N = 7, the others at the paper's N = 8.
//
// Render from this folder (dqjulia.inc is in ../../povray):
//   povray +L../../povray +W1200 +H800 +A0.3 paper-test2.pov

#version 3.7;
global_settings { assumed_gamma 1.0 }

#include "dqjulia.inc"

#declare Constants = array[6][8] {
  {-0.10,  0.80, -0.26,  0.15,  -0.23, -0.38, -0.86,  0.64},
  {-0.67, -0.54, -0.07,  0.02,   0.06, -0.53,  0.15, -0.27},
  {-0.98,  0.27,  0.40,  0.20,  -0.37, -0.41, -0.24, -0.34},
  { 0.35,  0.78,  0.85, -0.57,  -0.22,  0.06, -0.46,  0.05},
  {-0.17, -0.28,  0.11,  0.80,   0.06,  0.44, -0.66,  0.06},
  {-0.04,  0.95,  0.40, -0.43,   0.09, -0.45, -0.27, -0.31}
};
#declare Iterations = array[6] {5, 8, 8, 8, 7, 8};
#declare Slice = DQJ_Slice_Names("a.s,a.i,a.j");

camera {
  location <0, 0.6, -12.5>
  look_at <0, 0, 0>
  angle 50
  right x * image_width / image_height
}

light_source { <-6, 10, -12> color rgb <1, 0.96, 0.9> }
light_source { <8, -2, -6> color rgb <0.25, 0.3, 0.45> shadowless }
background { rgb <0.07, 0.08, 0.1> }

// About one pixel at the objects' distance on an 800-pixel-high image.
#declare Threshold = 2 * 12.5 * tan(radians(25 * 800 / 1200)) / 800;

#declare Tile = 0;
#while (Tile < 6)
  #declare C = array[8];
  #declare I = 0;
  #while (I < 8)
    #declare C[I] = Constants[Tile][I];
    #declare I = I + 1;
  #end
  #declare Trap = DQJ_Coloring_Function(C, "paper", Iterations[Tile], 4, Slice, "trap");
  object {
    DQJ_Isosurface(C, "paper", Iterations[Tile], 4, Slice, Threshold)
    texture {
      pigment {
        function { Trap(x, y, z) }
        color_map { [0 rgb <0.95, 0.75, 0.40>] [0.5 rgb <0.80, 0.30, 0.20>] [1 rgb <0.20, 0.25, 0.55>] }
      }
      finish { ambient 0.06 diffuse 0.8 phong 0.35 phong_size 24 }
    }
    rotate <-20, 30, 0>
    translate <(mod(Tile, 3) - 1) * 4.2, (div(Tile, 3) = 0 ? 2.1 : -2.1), 0>
  }
  #undef Trap
  #undef C
  #declare Tile = Tile + 1;
#end
