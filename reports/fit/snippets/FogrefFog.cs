// fogref export --engine unity: the unity fit at sun elevation 8 deg in reports/fit/engines.json
// fogref's units: radiance 1 = 1 cd/m^2, irradiance 1 = 1 lux; exposure 1.
// Unity built-in pipeline, Linear colour space (Player settings).  Unity is y-up, left-handed,
// metres: (x, y, z)_unity = (x, y, -z)_fogref.  Color values are sRGB: .gamma converts fogref's
// linear values.  fogref's fog coordinate: distance (Unity's built-in fog uses depth
// unless the shader computes the distance).
using UnityEngine;

public static class FogrefFog
{
    public static void Apply(Camera camera, Light sun)
    {
        RenderSettings.fog = true;
        RenderSettings.fogMode = FogMode.Exponential;
        RenderSettings.fogDensity = 0.00108430707f;
        RenderSettings.fogStartDistance = 0.0f;
        RenderSettings.fogEndDistance = 300.0f;
        RenderSettings.fogColor = new Color(0.151009058f, 0.18816455f, 0.264493906f).gamma;
        camera.transform.position = new Vector3(0.0f, 2.0f, -0.0f);
        camera.transform.rotation = Quaternion.LookRotation(new Vector3(0.140180794f, 0.327088519f, -0.934538627f), new Vector3(-0.0485204591f, 0.944993704f, 0.323469728f));
        camera.fieldOfView = 42.9956614f;  // vertical [deg]
        camera.nearClipPlane = 0.1f;
        camera.farClipPlane = 20000.0f;
        sun.type = LightType.Directional;
        sun.transform.rotation = Quaternion.LookRotation(new Vector3(-0.39995816f, -0.139173101f, 0.905905248f));
        sun.color = new Color(1.0f, 0.90625f, 0.75f).gamma;  // linear -> Unity's sRGB Color
        sun.intensity = 1.01859164f;  // built-in pipeline: irradiance / pi (its Standard BRDF leaves out the diffuse 1/pi)
    }
}
