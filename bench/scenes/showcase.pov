// Tessera benchmark scene "showcase" in POV-Ray 3.7 SDL; the twin of showcase.json.
// Coordinates are Tessera's (right-handed, +y up); "right -x*..." flips the image
// horizontally so that POV-Ray's left-handed camera frames it identically.
// See README.md for the matching conventions and the command lines.
#version 3.7;

#declare MaxDepth = 5;      // render.max_depth in the JSON
#declare FovY = 36;         // camera.fov_y in the JSON (vertical, degrees)

global_settings {
  assumed_gamma 1.0
  adc_bailout 0
  max_trace_level MaxDepth + 1
  ambient_light rgb <0.15, 0.15, 0.15>
}

camera {
  perspective
  location <0.3, 1.7, 6.6>
  look_at <0.2, 0.85, 0>
  sky y
  up y
  right -x * image_width / image_height
  angle 2 * degrees(atan(tan(radians(FovY / 2)) * image_width / image_height))
}

background { rgb <0.35, 0.5, 0.75> }

// Point lights without attenuation (Tessera attenuation [1, 0, 0]).
light_source { <-5, 7, 6> rgb <0.75, 0.72, 0.68> }
light_source { <6, 4, 3> rgb <0.35, 0.38, 0.45> }

// Tessera material {ambient KA, diffuse KD, specular KS, shininess n, reflection KR}
// is pigment KD with finish { ambient KA/KD diffuse 1 phong KS phong_size n reflection KR }.

// Checker of size 1: Tessera samples the floor 1e-4 below y = 0 (cell row y in [-1, 0));
// the 0.5 lift puts POV-Ray's sample in the same row.
plane {
  y, 0
  texture {
    checker
      texture { pigment { rgb <0.85, 0.85, 0.8> } finish { ambient 1 diffuse 1 } }
      texture { pigment { rgb <0.55, 0.1, 0.08> } finish { ambient 1 diffuse 1 } }
    translate <0, 0.5, 0>
  }
}

// mirror
sphere {
  <-1.9, 1.0, -0.8>, 1.0
  pigment { rgb 0.05 }
  finish { ambient 1 diffuse 1 phong 0.8 phong_size 300 reflection { 0.85 } }
}

// glass: need not match Tessera exactly (POV-Ray weights transmitted light its own way)
sphere {
  <0.5, 0.8, 1.4>, 0.8
  pigment { rgbt <1, 1, 1, 0.9> }
  finish { ambient 0 diffuse 0 phong 0.6 phong_size 200 reflection { 0 } }
  interior { ior 1.5 }
}

// glossy
sphere {
  <2.3, 0.75, -0.6>, 0.75
  pigment { rgb <0.1, 0.25, 0.7> }
  finish { ambient 1 diffuse 1 phong 0.5 phong_size 60 reflection { 0.15 } }
}
