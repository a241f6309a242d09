// fogref export --engine hdrp: the hdrp fit at sun elevation 8 deg in reports/fit/engines.json
// fogref's units: radiance 1 = 1 cd/m^2, irradiance 1 = 1 lux; exposure 1.
// HDRP (y-up, left-handed, metres: (x, y, z)_unity = (x, y, -z)_fogref).  The Fog override's
// colours go to the shader as they are (Fog.cs): linear.  The sun's Light colour is sRGB (.gamma).
using UnityEngine;
using UnityEngine.Rendering;
using UnityEngine.Rendering.HighDefinition;

public static class FogrefHdrpFog
{
    public static void Apply(VolumeProfile profile, Camera camera, Light sun)
    {
        if (!profile.TryGet(out Fog fog))
            fog = profile.Add<Fog>(true);
        fog.enabled.Override(true);
        fog.colorMode.Override(FogColorMode.ConstantColor);
        fog.color.Override(new Color(0.311830207f, 0.397140476f, 0.571477056f));
        fog.albedo.Override(new Color(0.9f, 0.9f, 0.9f));
        fog.meanFreePath.Override(281.898091f);
        fog.baseHeight.Override(-90.0955348f);
        fog.maximumHeight.Override(483.121203f);
        fog.maxFogDistance.Override(10000000.0f);
        camera.transform.position = new Vector3(0.0f, 2.0f, -0.0f);
        camera.transform.rotation = Quaternion.LookRotation(new Vector3(0.140180794f, 0.327088519f, -0.934538627f), new Vector3(-0.0485204591f, 0.944993704f, 0.323469728f));
        camera.fieldOfView = 42.9956614f;  // vertical [deg]
        camera.nearClipPlane = 0.1f;
        camera.farClipPlane = 20000.0f;
        sun.type = LightType.Directional;
        sun.transform.rotation = Quaternion.LookRotation(new Vector3(-0.39995816f, -0.139173101f, 0.905905248f));
        sun.color = new Color(1.0f, 0.90625f, 0.75f).gamma;  // linear -> Unity's sRGB Color
        sun.intensity = 3.2f;  // lux (HDRP)
    }
}
