#include "colors.inc"
global_settings { assumed_gamma 1.0 }
camera { location <0, 2, -5> look_at <0, 0.5, 0> angle 50 right x*image_width/image_height }
light_source { <5, 10, -5> color White }
plane { y, 0 pigment { checker color Gray20 color White scale 0.5 } }
#declare R = seed(1);
#for (I, 0, 4)
  sphere { <I - 2, 0.4, rand(R)>, 0.4 texture { pigment { color rgb <1, 0.2*I, 0> } finish { phong 0.8 } } }
#end
#macro Post(P) cylinder { P, P + y, 0.1 pigment { Red } } #end
Post(<-2, 0, 2>)
Post(<2, 0, 2>)
box { <-0.5, 0, -0.5>, <0.5, 1, 0.5> rotate y*30 translate <0, 0, 3> pigment { rgbf <0.8, 0.9, 1, 0.9> } interior { ior 1.5 } }
difference { sphere { 0, 1 } box { 0, 2 } pigment { Blue } finish { reflection 0.3 } translate <3, 1, 0> }
torus { 1, 0.2 pigment { wood color_map { [0 Tan] [1 Brown] } scale 0.2 } translate <-3, 0.2, 1> }
