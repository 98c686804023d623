// Tessera benchmark scene "many_lights" in POV-Ray 3.7 SDL; the twin of many_lights.json.
// 24 coloured point lights with quadratic fall-off over a field of spheres and boxes.
// Coordinates are Tessera's (right-handed, +y up); "right -x*..." flips the image
// horizontally so that POV-Ray's left-handed camera frames it identically.
// See README.md for the matching conventions and the command lines.
#version 3.7;

#declare MaxDepth = 3;      // render.max_depth in the JSON
#declare FovY = 40;         // camera.fov_y in the JSON (vertical, degrees)
#declare Fade = 4.0;        // fade_distance D; Tessera attenuation [0.5, 0, 0.5/D^2]

global_settings {
  assumed_gamma 1.0
  adc_bailout 0
  max_trace_level MaxDepth + 1
  ambient_light rgb <0.05, 0.05, 0.05>
}

camera {
  perspective
  location <0, 4.2, 8.2>
  look_at <0, 0.3, -0.4>
  sky y
  up y
  right -x * image_width / image_height
  angle 2 * degrees(atan(tan(radians(FovY / 2)) * image_width / image_height))
}

background { rgb <0.02, 0.02, 0.03> }

// POV-Ray fades a light by 2 / (1 + (d/D)^2) = 1 / (0.5 + 0.5 d^2/D^2).
#macro Lamp(P, C)
  light_source { P rgb C fade_distance Fade fade_power 2 }
#end

Lamp(<4.8, 2.2, 0.0>, <0.14, 0.021, 0.021>)
Lamp(<4.435, 2.2, 1.837>, <0.14, 0.066, 0.021>)
Lamp(<3.394, 2.2, 3.394>, <0.14, 0.11, 0.021>)
Lamp(<1.837, 2.2, 4.435>, <0.125, 0.14, 0.021>)
Lamp(<0.0, 2.2, 4.8>, <0.081, 0.14, 0.021>)
Lamp(<-1.837, 2.2, 4.435>, <0.036, 0.14, 0.021>)
Lamp(<-3.394, 2.2, 3.394>, <0.021, 0.14, 0.051>)
Lamp(<-4.435, 2.2, 1.837>, <0.021, 0.14, 0.095>)
Lamp(<-4.8, 2.2, 0.0>, <0.021, 0.14, 0.14>)
Lamp(<-4.435, 2.2, -1.837>, <0.021, 0.095, 0.14>)
Lamp(<-3.394, 2.2, -3.394>, <0.021, 0.051, 0.14>)
Lamp(<-1.837, 2.2, -4.435>, <0.036, 0.021, 0.14>)
Lamp(<-0.0, 2.2, -4.8>, <0.081, 0.021, 0.14>)
Lamp(<1.837, 2.2, -4.435>, <0.125, 0.021, 0.14>)
Lamp(<3.394, 2.2, -3.394>, <0.14, 0.021, 0.11>)
Lamp(<4.435, 2.2, -1.837>, <0.14, 0.021, 0.066>)
Lamp(<2.033, 3.6, 0.842>, <0.05, 0.05, 0.05>)
Lamp(<0.842, 3.6, 2.033>, <0.05, 0.05, 0.05>)
Lamp(<-0.842, 3.6, 2.033>, <0.05, 0.05, 0.05>)
Lamp(<-2.033, 3.6, 0.842>, <0.05, 0.05, 0.05>)
Lamp(<-2.033, 3.6, -0.842>, <0.05, 0.05, 0.05>)
Lamp(<-0.842, 3.6, -2.033>, <0.05, 0.05, 0.05>)
Lamp(<0.842, 3.6, -2.033>, <0.05, 0.05, 0.05>)
Lamp(<2.033, 3.6, -0.842>, <0.05, 0.05, 0.05>)

// Tessera material {ambient KA, diffuse KD, specular KS, shininess n, reflection KR}
// is pigment KD with finish { ambient KA/KD diffuse 1 phong KS phong_size n reflection KR }.
plane { y, 0 pigment { rgb <0.6, 0.6, 0.6> } finish { ambient 1 diffuse 1 } }
#declare Box = texture { pigment { rgb <0.75, 0.7, 0.6> } finish { ambient 1 diffuse 1 phong 0.2 phong_size 20 } }
#declare S0 = texture { pigment { rgb <0.8, 0.2, 0.15> } finish { ambient 1 diffuse 1 phong 0.5 phong_size 50 reflection { 0.2 } } }
#declare S1 = texture { pigment { rgb <0.2, 0.7, 0.25> } finish { ambient 1 diffuse 1 phong 0.5 phong_size 50 reflection { 0.2 } } }
#declare S2 = texture { pigment { rgb <0.2, 0.35, 0.85> } finish { ambient 1 diffuse 1 phong 0.5 phong_size 50 reflection { 0.2 } } }
#declare S3 = texture { pigment { rgb <0.85, 0.75, 0.2> } finish { ambient 1 diffuse 1 phong 0.5 phong_size 50 reflection { 0.2 } } }
#declare S4 = texture { pigment { rgb <0.7, 0.7, 0.7> } finish { ambient 1 diffuse 1 phong 0.5 phong_size 50 reflection { 0.2 } } }
#declare S5 = texture { pigment { rgb <0.7, 0.25, 0.7> } finish { ambient 1 diffuse 1 phong 0.5 phong_size 50 reflection { 0.2 } } }

sphere { <-2.6, 0.38, -1.95>, 0.38 texture { S0 } }
sphere { <-2.6, 0.54, -0.65>, 0.54 texture { S1 } }
sphere { <-2.6, 0.46, 0.65>, 0.46 texture { S2 } }
sphere { <-2.6, 0.38, 1.95>, 0.38 texture { S3 } }
sphere { <-1.3, 0.38, -1.95>, 0.38 texture { S4 } }
sphere { <-1.3, 0.54, -0.65>, 0.54 texture { S5 } }
sphere { <-1.3, 0.46, 0.65>, 0.46 texture { S0 } }
sphere { <-1.3, 0.38, 1.95>, 0.38 texture { S1 } }
sphere { <0.0, 0.38, -1.95>, 0.38 texture { S2 } }
sphere { <0.0, 0.54, -0.65>, 0.54 texture { S3 } }
sphere { <0.0, 0.46, 0.65>, 0.46 texture { S4 } }
sphere { <0.0, 0.38, 1.95>, 0.38 texture { S5 } }
sphere { <1.3, 0.38, -1.95>, 0.38 texture { S0 } }
sphere { <1.3, 0.54, -0.65>, 0.54 texture { S1 } }
sphere { <1.3, 0.46, 0.65>, 0.46 texture { S2 } }
sphere { <1.3, 0.38, 1.95>, 0.38 texture { S3 } }
sphere { <2.6, 0.38, -1.95>, 0.38 texture { S4 } }
sphere { <2.6, 0.54, -0.65>, 0.54 texture { S5 } }
sphere { <2.6, 0.46, 0.65>, 0.46 texture { S0 } }
sphere { <2.6, 0.38, 1.95>, 0.38 texture { S1 } }
box { <-3.8, 0, -3.8>, <-3.0, 1.4, -3.0> texture { Box } }
box { <3.0, 0, -3.8>, <3.8, 0.9, -3.0> texture { Box } }
box { <-0.5, 0, -3.9>, <0.5, 0.5, -3.3> texture { Box } }
