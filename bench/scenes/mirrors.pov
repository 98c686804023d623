// Tessera benchmark scene "mirrors" in POV-Ray 3.7 SDL; the twin of mirrors.json.
// Two facing mirrors and reflective spheres, 16 bounces.
// Coordinates are Tessera's (right-handed, +y up); "right -x*..." flips the image
// horizontally so that POV-Ray's left-handed camera frames it identically.
// See README.md for the matching conventions and the command lines.
#version 3.7;

#declare MaxDepth = 16;     // render.max_depth in the JSON
#declare FovY = 50;         // camera.fov_y in the JSON (vertical, degrees)

global_settings {
  assumed_gamma 1.0
  adc_bailout 0
  max_trace_level MaxDepth + 1
  ambient_light rgb <0.12, 0.12, 0.12>
}

camera {
  perspective
  location <2.0, 1.5, 2.6>
  look_at <-2.5, 1.0, 0.3>
  sky y
  up y
  right -x * image_width / image_height
  angle 2 * degrees(atan(tan(radians(FovY / 2)) * image_width / image_height))
}

background { rgb <0.3, 0.4, 0.6> }

// Point lights without attenuation (Tessera attenuation [1, 0, 0]).
light_source { <0, 3.5, 3> rgb <0.7, 0.68, 0.64> }
light_source { <1.5, 2.5, -4> rgb <0.35, 0.35, 0.4> }

// Tessera material {ambient KA, diffuse KD, specular KS, shininess n, reflection KR}
// is pigment KD with finish { ambient KA/KD diffuse 1 phong KS phong_size n reflection KR }.
#declare Mirror = texture { pigment { rgb 0.03 }
  finish { ambient 1 diffuse 1 phong 0.3 phong_size 200 reflection { rgb <0.86, 0.9, 0.88> } } }
#declare Chrome = texture { pigment { rgb 0.05 }
  finish { ambient 1 diffuse 1 phong 0.8 phong_size 250 reflection { 0.8 } } }
#declare Red = texture { pigment { rgb <0.7, 0.1, 0.08> }
  finish { ambient 1 diffuse 1 phong 0.5 phong_size 60 reflection { 0.3 } } }
#declare Gold = texture { pigment { rgb <0.6, 0.45, 0.12> }
  finish { ambient 1 diffuse 1 phong 0.6 phong_size 80 reflection { 0.4 } } }
#declare Blue = texture { pigment { rgb <0.1, 0.2, 0.65> }
  finish { ambient 1 diffuse 1 phong 0.4 phong_size 40 reflection { 0.2 } } }
#declare Wall = texture { pigment { rgb <0.3, 0.45, 0.4> } finish { ambient 1 diffuse 1 } }

// Checker of size 0.5: Tessera samples the floor just below y = 0 (cell row y in [-0.5, 0));
// the lift by half a cell, before the scale, puts POV-Ray's sample in the same row.
plane {
  y, 0
  texture {
    checker
      texture { pigment { rgb <0.8, 0.78, 0.72> } finish { ambient 1 diffuse 1 } }
      texture { pigment { rgb <0.12, 0.12, 0.14> } finish { ambient 1 diffuse 1 } }
    translate <0, 0.5, 0>
    scale 0.5
  }
}

plane { x, -2.5 texture { Mirror } }   // normal +x
plane { -x, -2.5 texture { Mirror } }  // x = 2.5, normal -x
plane { z, -8 texture { Wall } }

sphere { <-0.9, 0.7, -1.0>, 0.7 texture { Chrome } }
sphere { <0.8, 0.5, 0.6>, 0.5 texture { Red } }
sphere { <0.9, 0.6, -3.2>, 0.6 texture { Gold } }
sphere { <-1.2, 0.4, 1.6>, 0.4 texture { Blue } }
sphere { <-0.3, 1.9, -2.2>, 0.35 texture { Chrome } }
box { <-0.4, 0, -5.4>, <0.4, 1.6, -4.6> texture { Blue } }
