#version 450
// The backdrop (viewer_backdrop.h): one channel of the image as grey, or its RGB, scaled, alpha ignored. The
// target is sRGB, so the value is shown as linear light, as the lighting would use it.
layout(set = 0, binding = 0) uniform sampler2D image;
layout(push_constant) uniform Shows {
  int channel;       // -1 = RGB, 0..3 = that channel as grey (BackdropChannel)
  float scale;       // multiplies the value first
  uint compressHdr;  // 1 = then v / (1 + v) per channel
} shows;
layout(location = 0) in vec2 uv;
layout(location = 0) out vec4 color;

void main() {
  vec4 texel = texture(image, uv);
  vec3 v = (shows.channel < 0 ? texel.rgb : vec3(texel[shows.channel])) * shows.scale;
  v = max(v, vec3(0.0));  // kept-history marks (-1) and negative noise read as black
  if (shows.compressHdr != 0u) v /= 1.0 + v;
  color = vec4(v, 1.0);
}
