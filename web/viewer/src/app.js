// The lanemap viewer's page: Leaflet with no tiles (the base layer is the OSM file's roads, drawn
// from the skeleton), updated from the viewer's server-sent event stream (/api/events; polling
// /api/state when the stream is unavailable). window.lanemapViewer.stats says what is drawn, for
// the browser test (tests/viewer/browser_test.cc).
'use strict';
(function () {
  const COVERAGE = { never_driven: '#9aa3ad', driven: '#e39a2d', mapped: '#2f9e44' };
  const BOUNDARY = {
    dashed: { color: '#ffffff', weight: 2, dashArray: '6 6' },
    solid: { color: '#ffffff', weight: 2 },
    solid_solid: { color: '#f2c40f', weight: 3 },
    curbstone: { color: '#c8c8c8', weight: 3 },
    virtual: { color: '#8e9aab', weight: 1, dashArray: '2 4' },
    stop_line: { color: '#e03131', weight: 3 },
  };

  // ?zoom=N: the zoom level when following the car (default 18); ?follow=0: do not follow it.
  const params = new URLSearchParams(location.search);
  const followZoom = Math.min(20, Math.max(10, parseInt(params.get('zoom') || '18', 10) || 18));
  if (params.get('follow') === '0') document.getElementById('follow').checked = false;

  const stats = {
    stateUpdates: 0, skeletonRoads: 0, roadLanesDrawn: 0, connectionsDrawn: 0, lanesByRoad: {},
    carUpdates: 0, firstCar: null, lastCar: null, carMovedM: 0, bevUpdates: 0, bevOpenUpdates: 0, bevRoad: null,
    processes: [], mapVersion: -1, transport: 'none',
  };

  const map = L.map('map', { zoomControl: true, attributionControl: true });
  map.attributionControl.setPrefix('Leaflet');
  map.attributionControl.addAttribution('Map data &copy; OpenStreetMap contributors, ODbL');
  map.setView([0, 0], 2);
  const panes = [['skeleton', 350], ['bev', 380], ['trail', 400], ['lanes', 420], ['car', 460]];
  for (const [name, z] of panes) map.createPane(name).style.zIndex = z;

  function tagTable(props) {
    const rows = Object.keys(props).map(function (k) {
      let v = props[k];
      if (v === null || v === undefined) v = '–';
      else if (Array.isArray(v)) v = v.join(', ') || '–';
      else if (typeof v === 'object') v = JSON.stringify(v);
      return '<tr><th>' + escapeHtml(k) + '</th><td>' + escapeHtml(String(v)) + '</td></tr>';
    });
    return '<table class="tags">' + rows.join('') + '</table>';
  }
  function escapeHtml(s) {
    return s.replace(/[&<>"']/g, function (c) {
      return { '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;' }[c];
    });
  }

  const skeletonLayer = L.geoJSON(null, {
    pane: 'skeleton',
    style: function (f) { return { color: COVERAGE[f.properties.coverage] || '#999', weight: f.properties.coverage === 'never_driven' ? 3 : 5, opacity: 0.9 }; },
    onEachFeature: function (f, layer) { layer.bindPopup(tagTable(f.properties)); },
  }).addTo(map);

  const lanesLayer = L.geoJSON(null, {
    pane: 'lanes',
    style: function (f) {
      const p = f.properties;
      if (p.feature === 'lanelet') {
        const junction = p.kind === 'intersection';
        if (junction) return { stroke: false, fillColor: '#3d6fb6', fillOpacity: 0.35 };
        // As opaque as the mapper is sure of the lane (0..1; none said: fully); a partial road's
        // lanes (mapped as far as the drive went) outlined dashed.
        const sure = typeof p.confidence === 'number' ? Math.max(0, Math.min(1, p.confidence)) : 1;
        const style = { stroke: false, fillColor: '#4a4f57', fillOpacity: 0.2 + 0.55 * sure };
        if (p.partial) Object.assign(style, { stroke: true, color: '#f08c00', weight: 2, dashArray: '6 4', opacity: 0.9 });
        return style;
      }
      if (p.feature === 'centre_line') return { color: p.kind === 'intersection' ? '#1c4f99' : '#66d9e8', weight: 1.5, opacity: 0.9 };
      if (p.feature === 'regulatory_element') return { color: p.kind === 'traffic_light' ? '#f59f00' : '#e03131', weight: 4, opacity: 0.9 };
      if (p.feature === 'crosswalk') return { stroke: false, fillColor: '#f8f9fa', fillOpacity: 0.45 };
      return BOUNDARY[p.type] || BOUNDARY.virtual;
    },
    pointToLayer: function (f, latlng) { return L.circleMarker(latlng, { radius: 2, pane: 'lanes' }); },
    onEachFeature: function (f, layer) { layer.bindPopup(tagTable(f.properties)); },
  }).addTo(map);

  let bevOverlay = null;
  const bevGroup = L.layerGroup().addTo(map);
  const trail = L.polyline([], { pane: 'trail', color: '#d6336c', weight: 2, opacity: 0.7, interactive: false }).addTo(map);
  let trailCount = 0;
  const carIcon = L.divIcon({
    className: 'car-icon', iconSize: [22, 22], iconAnchor: [11, 11],
    html: '<svg width="22" height="22" viewBox="-11 -11 22 22"><g id="car-arrow">' +
          '<circle r="9" fill="#fff" stroke="#000" stroke-width="1.5"/>' +
          '<path d="M0,-7 L5,5 L0,2 L-5,5 Z" fill="#d6336c"/></g></svg>',
  });
  const car = L.marker([0, 0], { icon: carIcon, pane: 'car', interactive: false });

  window.lanemapViewer = { stats: stats, map: map, lanesLayer: lanesLayer, skeletonLayer: skeletonLayer };

  L.control.layers(null, {
    'OSM roads (coverage)': skeletonLayer, 'BEV of the open / last road': bevGroup, 'mapped lanes': lanesLayer,
    'trail': trail,
  }, { collapsed: true }).addTo(map);
  L.control.scale({ imperial: false }).addTo(map);

  function getJson(url) {
    return fetch(url, { cache: 'no-store' }).then(function (r) {
      if (!r.ok) throw new Error(url + ': ' + r.status);
      return r.json();
    });
  }

  let fitted = false;
  let loadingSkeleton = false, skeletonVersion = -1, wantSkeleton = 0;
  function loadSkeleton(version) {
    wantSkeleton = version;
    if (loadingSkeleton || version === skeletonVersion) return;
    loadingSkeleton = true;
    getJson('api/skeleton.geojson').then(function (g) {
      skeletonLayer.clearLayers();
      skeletonLayer.addData(g);
      stats.skeletonRoads = g.features.length;
      skeletonVersion = version;
      // The whole OSM extract until the car is known (following it sets the view then).
      if (!fitted && !followed && g.features.length) map.fitBounds(skeletonLayer.getBounds());
      fitted = true;
    }).catch(console.error).finally(function () {
      loadingSkeleton = false;
      if (wantSkeleton !== skeletonVersion) loadSkeleton(wantSkeleton);
    });
  }

  let loadingLanes = false, wantLanes = -1;
  function loadLanes(version) {
    wantLanes = version;
    if (loadingLanes || version === stats.mapVersion) return;
    loadingLanes = true;
    getJson('api/lanes.geojson').then(function (g) {
      lanesLayer.clearLayers();
      lanesLayer.addData(g);
      // Lanes drawn: distinct lanelets with a polygon or a centre line, per road.
      const byRoad = {}, connections = {};
      let roadLanes = 0;
      for (const f of g.features) {
        const p = f.properties;
        if (p.feature !== 'lanelet' && p.feature !== 'centre_line') continue;
        const id = p.feature === 'lanelet' ? p.id : p.lanelet;
        if (p.kind === 'intersection') { connections[id] = true; continue; }
        const road = String(p.road_id);
        byRoad[road] = byRoad[road] || {};
        byRoad[road][id] = true;
      }
      stats.lanesByRoad = {};
      for (const r of Object.keys(byRoad)) { stats.lanesByRoad[r] = Object.keys(byRoad[r]).length; roadLanes += stats.lanesByRoad[r]; }
      stats.roadLanesDrawn = roadLanes;
      stats.connectionsDrawn = Object.keys(connections).length;
      stats.mapVersion = version;
      document.getElementById('road-lanes').textContent = roadLanes;
      document.getElementById('connections').textContent = stats.connectionsDrawn;
    }).catch(console.error).finally(function () {
      loadingLanes = false;
      if (wantLanes !== stats.mapVersion) loadLanes(wantLanes);
    });
  }

  let loadingTrail = false;
  function loadTrail(count) {
    if (loadingTrail || count <= trailCount) return;
    loadingTrail = true;
    getJson('api/trail?from=' + trailCount).then(function (t) {
      if (t.from > trailCount) trail.setLatLngs([]);  // the server dropped old points
      for (const p of t.points) trail.addLatLng([p[1], p[0]]);
      trailCount = t.from + t.points.length;
    }).catch(console.error).finally(function () { loadingTrail = false; });
  }

  let bevVersion = -1;
  function showBev(bev) {
    if (!bev || bev.version === bevVersion) return;
    bevVersion = bev.version;
    const url = 'api/bev.png?v=' + bev.version;
    // The open road's picture changes about once a second: swap the image in place (no flicker).
    if (bevOverlay) {
      bevOverlay.setUrl(url);
      bevOverlay.setBounds(L.latLngBounds(bev.bounds));
    } else {
      bevOverlay = L.imageOverlay(url, bev.bounds, { pane: 'bev', opacity: 0.9, interactive: false });
      bevGroup.addLayer(bevOverlay);
    }
    stats.bevUpdates += 1;
    if (bev.open) stats.bevOpenUpdates += 1;
    stats.bevRoad = bev.road_id;
    document.getElementById('bev-road').textContent = 'road ' + bev.road_id + (bev.open ? ' (open, live)' : ' (closed)');
  }

  function metres(a, b) {
    const k = Math.PI / 180, R = 6371008.8;
    const x = (b[1] - a[1]) * k * Math.cos((a[0] + b[0]) * k / 2), y = (b[0] - a[0]) * k;
    return Math.hypot(x, y) * R;
  }

  let followed = false;
  function showCar(c) {
    if (!c) return;
    const ll = [c.lat, c.lon];
    if (!map.hasLayer(car)) car.addTo(map);
    car.setLatLng(ll);
    const g = car.getElement() && car.getElement().querySelector('#car-arrow');
    const bearing = 90 - c.heading * 180 / Math.PI;  // ENU heading (east, counter-clockwise) -> compass
    if (g) g.setAttribute('transform', 'rotate(' + bearing.toFixed(1) + ')');
    stats.carUpdates += 1;
    if (!stats.firstCar) stats.firstCar = ll;
    stats.lastCar = ll;
    stats.carMovedM = metres(stats.firstCar, ll);
    if (document.getElementById('follow').checked) {
      if (!followed) { map.setView(ll, followZoom, { animate: false }); followed = true; }
      else map.panTo(ll, { animate: false });
    }
  }

  function fmt(v, digits) { return v === null || v === undefined ? '–' : Number(v).toFixed(digits); }

  function showProcesses(list) {
    const body = document.querySelector('#status tbody');
    const rows = list.map(function (p) {
      const tr = document.createElement('tr');
      tr.className = p.behind ? 'behind' : 'ok';
      tr.dataset.process = p.process;
      tr.title = p.behind ? 'behind: ' + p.reason : p.state;
      const cells = [p.process, p.host, fmt(p.cpu * 100, 0) + ' %', String(p.drops),
                     fmt(p.latency_p50_ms, 0) + ' / ' + fmt(p.latency_p99_ms, 0), fmt(p.age_s, 1) + ' s'];
      for (const c of cells) {
        const td = document.createElement('td');
        td.textContent = c;
        tr.appendChild(td);
      }
      return tr;
    });
    body.replaceChildren.apply(body, rows);
    stats.processes = list.map(function (p) { return { name: p.process, behind: p.behind }; });
  }

  function applyState(s) {
    stats.stateUpdates += 1;
    loadSkeleton(s.coverage.version);
    if (s.map.version !== stats.mapVersion) loadLanes(s.map.version);
    loadTrail(s.trail_count);
    showBev(s.bev);
    showCar(s.car);
    showProcesses(s.processes);
    document.getElementById('roads-mapped').textContent = s.map.roads;
    document.getElementById('open-road').textContent = s.open_road >= 0 ? 'road ' + s.open_road : '–';
    document.getElementById('coverage').textContent =
      s.coverage.mapped + ' mapped, ' + s.coverage.driven + ' driven, ' + s.coverage.never_driven + ' never driven';
  }

  // Updates: the event stream; polling once a second while it is down.
  let pollTimer = null;
  function poll() {
    getJson('api/state').then(applyState).catch(function () {
      document.getElementById('connection').textContent = 'viewer unreachable, retrying…';
    });
  }
  function connect() {
    if (!window.EventSource) { stats.transport = 'polling'; pollTimer = setInterval(poll, 1000); return; }
    const es = new EventSource('api/events');
    es.addEventListener('state', function (e) {
      if (pollTimer) { clearInterval(pollTimer); pollTimer = null; }
      stats.transport = 'events';
      document.getElementById('connection').textContent = 'live (' + location.host + ')';
      applyState(JSON.parse(e.data));
    });
    es.onerror = function () {
      document.getElementById('connection').textContent = 'event stream lost, polling…';
      stats.transport = 'polling';
      if (!pollTimer) pollTimer = setInterval(poll, 1000);
    };
  }
  poll();
  connect();
})();
