camera { location <0.5, 1.2, -3> look_at <0.5, 0.5, 0> }
light_source { <2, 4, -3>, rgb 1 }
plane { y, -0.01 pigment { checker rgb 0.8 rgb 0.6 } }
mesh2 {
  vertex_vectors { 5, <0, 0, 0>, <1, 0, 0>, <1, 1, 0>, <0, 1, 0>, <0.5, 1.5, 0> }
  texture_list { 2, texture { pigment { rgb <1, 0.1, 0.1> } } texture { pigment { rgb <0.1, 0.2, 1> } } }
  face_indices { 3, <0, 1, 3>, 0, <1, 2, 3>, 1, <3, 2, 4> }
  pigment { rgb <0.1, 0.9, 0.1> }
  rotate <0, -20, 0>
}
