#include "common/net/job_spec_wire.h"

namespace portico {

void toWire(const JobSettings& settings, wire::JobSpec::Builder spec) {
  spec.setStore(settings.store);
  spec.setOutput(settings.output);
  spec.setAccel(settings.accel);
  spec.setRenderAccel(settings.renderAccel);
  spec.setPhotons(settings.photons);
  spec.setSpp(settings.spp);
  spec.setSeed(settings.seed);
  spec.setWidth(settings.width);
  spec.setHeight(settings.height);
  spec.setLightSamples(settings.lightSamples);
  spec.setPhotonK(settings.photonK);
  spec.setPhotonRadius(settings.photonRadius);
  spec.setExposure(settings.exposure);
  spec.setGather(settings.gather);
  spec.setLightHops(settings.lightHops);
  spec.setLightSampling(settings.lightSampling == LightSampling::Scan ? wire::LightSampling::SCAN
                                                                     : wire::LightSampling::TREE);
  spec.setIrradiance(settings.irradiance == JobSettings::Irradiance::Knn ? wire::Irradiance::KNN
                                                                          : wire::Irradiance::PRECOMPUTED);
  spec.setAov(settings.aov == JobSettings::Aov::Cells     ? wire::Aov::CELLS
              : settings.aov == JobSettings::Aov::Portals ? wire::Aov::PORTALS
                                                          : wire::Aov::RADIANCE);
  spec.setCameraName(settings.cameraName);
  if (settings.camera) {
    const JobCamera& c = *settings.camera;
    auto camera = spec.initCamera();
    camera.setFromX(c.lookFrom.x), camera.setFromY(c.lookFrom.y), camera.setFromZ(c.lookFrom.z);
    camera.setAtX(c.lookAt.x), camera.setAtY(c.lookAt.y), camera.setAtZ(c.lookAt.z);
    camera.setUpX(c.up.x), camera.setUpY(c.up.y), camera.setUpZ(c.up.z);
    camera.setFovY(c.fovYDegrees);
    camera.setCell(c.cell);
  }
  if (settings.targetError) spec.getTargetError().setValue(*settings.targetError);
  if (settings.timeLimitSeconds) spec.getTimeLimit().setSeconds(*settings.timeLimitSeconds);
  spec.setMaxPasses(settings.maxPasses);
  if (settings.analysis) {
    auto analysis = spec.initAnalysis();
    analysis.setSensors(settings.analysis->sensors);
    analysis.setDaylightFactor(settings.analysis->daylightFactor);
  }
  if (settings.luminance) {
    auto luminance = spec.initLuminance();
    luminance.setFalseColor(settings.luminance->falseColor);
    luminance.setFalseColorMaximum(settings.luminance->falseColorMaximum);
    luminance.setFalseColorDecades(settings.luminance->falseColorDecades);
    luminance.setFalseColorSteps(settings.luminance->falseColorSteps);
  }
  if (const DaylightSettings& d = settings.daylight; d.any()) {
    auto daylight = spec.initDaylight();
    daylight.setSky(static_cast<wire::SkyKind>(d.sky));
    daylight.setSkyR(d.skyRadiance.x), daylight.setSkyG(d.skyRadiance.y), daylight.setSkyB(d.skyRadiance.z);
    daylight.setTurbidity(d.turbidity);
    daylight.setSun(d.sun);
    daylight.setSunAzimuth(d.sunAzimuthDegrees);
    daylight.setSunElevation(d.sunElevationDegrees);
    daylight.setSunR(d.sunIrradiance.x), daylight.setSunG(d.sunIrradiance.y), daylight.setSunB(d.sunIrradiance.z);
    if (d.sunTime) {
      auto sunTime = daylight.initSunTime();
      sunTime.setUnixSeconds(d.sunTime->unixSeconds);
      if (d.sunTime->latitudeDegrees) sunTime.getLatitude().setDegrees(*d.sunTime->latitudeDegrees);
      if (d.sunTime->longitudeDegrees) sunTime.getLongitude().setDegrees(*d.sunTime->longitudeDegrees);
      if (d.sunTime->northAzimuthDegrees) sunTime.getNorthAzimuth().setDegrees(*d.sunTime->northAzimuthDegrees);
    }
  }
}

JobSettings jobSettingsFromWire(wire::JobSpec::Reader spec) {
  JobSettings settings;
  settings.store = spec.getStore();
  settings.output = spec.getOutput();
  settings.accel = spec.getAccel();
  settings.renderAccel = spec.getRenderAccel();
  settings.photons = spec.getPhotons();
  settings.spp = spec.getSpp();
  settings.seed = spec.getSeed();
  settings.width = spec.getWidth();
  settings.height = spec.getHeight();
  settings.lightSamples = spec.getLightSamples();
  settings.photonK = spec.getPhotonK();
  settings.photonRadius = spec.getPhotonRadius();
  settings.exposure = spec.getExposure();
  settings.gather = spec.getGather();
  settings.lightHops = spec.getLightHops();
  settings.lightSampling = spec.getLightSampling() == wire::LightSampling::SCAN ? LightSampling::Scan : LightSampling::Tree;
  settings.irradiance = spec.getIrradiance() == wire::Irradiance::KNN ? JobSettings::Irradiance::Knn
                                                                       : JobSettings::Irradiance::Precomputed;
  settings.aov = spec.getAov() == wire::Aov::CELLS     ? JobSettings::Aov::Cells
                 : spec.getAov() == wire::Aov::PORTALS ? JobSettings::Aov::Portals
                                                       : JobSettings::Aov::Radiance;
  settings.cameraName = spec.getCameraName();
  if (spec.hasCamera()) {
    const auto camera = spec.getCamera();
    settings.camera = JobCamera{Vec3(camera.getFromX(), camera.getFromY(), camera.getFromZ()),
                                Vec3(camera.getAtX(), camera.getAtY(), camera.getAtZ()),
                                Vec3(camera.getUpX(), camera.getUpY(), camera.getUpZ()), camera.getFovY(),
                                camera.getCell()};
  }
  if (spec.getTargetError().isValue()) settings.targetError = spec.getTargetError().getValue();
  if (spec.getTimeLimit().isSeconds()) settings.timeLimitSeconds = spec.getTimeLimit().getSeconds();
  settings.maxPasses = spec.getMaxPasses();
  if (spec.hasAnalysis())
    settings.analysis = AnalysisSettings{spec.getAnalysis().getSensors(), spec.getAnalysis().getDaylightFactor()};
  if (spec.hasLuminance()) {
    const auto luminance = spec.getLuminance();
    settings.luminance = LuminanceImage{luminance.getFalseColor(), luminance.getFalseColorMaximum(),
                                        luminance.getFalseColorDecades(), luminance.getFalseColorSteps()};
  }
  if (spec.hasDaylight()) {
    const auto daylight = spec.getDaylight();
    DaylightSettings& d = settings.daylight;
    const auto sky = daylight.getSky();
    d.sky = sky <= wire::SkyKind::OVERCAST ? static_cast<DaylightSettings::Sky>(sky) : DaylightSettings::Sky::None;
    d.skyRadiance = Vec3(daylight.getSkyR(), daylight.getSkyG(), daylight.getSkyB());
    d.turbidity = daylight.getTurbidity();
    d.sun = daylight.getSun();
    d.sunAzimuthDegrees = daylight.getSunAzimuth();
    d.sunElevationDegrees = daylight.getSunElevation();
    d.sunIrradiance = Vec3(daylight.getSunR(), daylight.getSunG(), daylight.getSunB());
    if (daylight.hasSunTime()) {
      const auto sunTime = daylight.getSunTime();
      SunTime& t = d.sunTime.emplace();
      t.unixSeconds = sunTime.getUnixSeconds();
      if (sunTime.getLatitude().isDegrees()) t.latitudeDegrees = sunTime.getLatitude().getDegrees();
      if (sunTime.getLongitude().isDegrees()) t.longitudeDegrees = sunTime.getLongitude().getDegrees();
      if (sunTime.getNorthAzimuth().isDegrees()) t.northAzimuthDegrees = sunTime.getNorthAzimuth().getDegrees();
    }
  }
  return settings;
}

}  // namespace portico
